#include "server/grade/grade_runner.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "renderer/compare/image.h"
#include "renderer/util/input_error.h"
#include "renderer/util/path_confinement.h"
#include "server/client/job_submission.h"
#include "renderer/util/atomic_file.h"
#include "server/common/scene_hash.h"
#include "server/embedded/job_renderer.h"
#include "server/grade/student_program.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr std::uintmax_t kMaxImageBytes = 64ull << 20;  // a 640x480 render is well under 1 MiB

// A distinct scene of the rubric, rendered once: its EXR, its sRGB preview, and the job as a
// self-contained folder a student program reads ({job}).
struct Reference {
  fs::path exr, preview, job_folder, job_file;
  fs::path display;  // what feedback shows of it: the preview's pixels, written once
  int width = 0, height = 0;
  // Decoded once, shared read-only by every student's comparison.
  std::shared_ptr<const Image> exr_image, preview_image;
};

std::string figure_label(const std::string& figure) {
  static const std::map<std::string, std::string> labels = {
      {"flip_mean", "FLIP mean"},      {"psnr_db", "PSNR (dB)"}, {"ssim", "mean SSIM"},
      {"failing_percent", "failing pixels (%)"}, {"differing_percent", "differing pixels (%)"},
      {"pass_percent", "pixel-channels passing (%)"}};
  const auto it = labels.find(figure);
  return it == labels.end() ? figure : it->second;
}

std::string points_text(double points) { return fmt::format("{:.4g}", points); }

// Renders every distinct job of the rubric once; a job whose scene is already under
// <output>/references (same scene hash) is not rendered again.
std::map<fs::path, Reference> render_references(const Rubric& rubric, const GradeOptions& options) {
  std::map<fs::path, Reference> out;
  std::optional<JobRenderer> renderer;
  for (const GradeTask& task : rubric.tasks) {
    if (out.count(task.job) != 0) continue;
    JobLoadOptions load;
    load.asset_root = rubric.asset_root;
    const JobSubmission submission = make_job_submission(task.job, load, {});
    const std::string hash = scene_hash(submission.spec);
    const fs::path dir = options.output_dir / "references" / hash;
    Reference ref;
    ref.exr = dir / "reference.exr";
    ref.preview = dir / "reference.png";
    ref.job_folder = dir / "job";
    ref.job_file = ref.job_folder / submission.spec.file_name();
    std::error_code ec;
    if (!fs::exists(ref.exr, ec) || !fs::exists(ref.preview, ec)) {
      if (!renderer) renderer.emplace(options.scheduler, options.threads);
      fs::create_directories(dir);
      renderer->render(submission, ref.exr, ref.preview);
    }
    // The job a student program reads: the job text with its files laid out beside it by the
    // names the job uses, so nothing of the grader's tree but this folder is mounted.
    fs::create_directories(ref.job_folder);
    for (const v1::AssetRef& asset : submission.spec.assets()) {
      const fs::path target = ref.job_folder / asset.path();
      fs::create_directories(target.parent_path());
      fs::copy_file(submission.files.at(asset.sha256()), target, fs::copy_options::overwrite_existing);
    }
    write_text_atomically(ref.job_file, submission.spec.job_json());
    ref.preview_image = std::make_shared<const Image>(read_image(ref.preview));
    ref.exr_image = std::make_shared<const Image>(read_image(ref.exr));
    ref.width = ref.preview_image->width;
    ref.height = ref.preview_image->height;
    ref.display = dir / "reference.display.png";
    write_png_image(to_display(*ref.preview_image), ref.display);
    out.emplace(task.job, ref);
  }
  return out;
}

// The student's image at `path` (inside `root`), or the reason it cannot be used.
std::optional<Image> read_student_image(const fs::path& root, const fs::path& relative, const Reference& ref,
                                        std::string& reason) {
  const std::string name = relative.generic_string();
  const fs::path path = root / relative;
  std::error_code ec;
  const fs::file_status link = fs::symlink_status(path, ec);
  if (!fs::exists(link)) {
    reason = fmt::format("{} is missing from the submission", name);
    return std::nullopt;
  }
  const auto resolved = resolve_within(fs::weakly_canonical(root, ec), path);
  if (!resolved) {
    reason = fmt::format("{} is a link to something outside the submission folder; it was not read", name);
    return std::nullopt;
  }
  if (!fs::is_regular_file(*resolved, ec)) {
    reason = fmt::format("{} is {}, not an image file", name, fs::is_directory(*resolved, ec) ? "a folder" : "not a regular file");
    return std::nullopt;
  }
  if (fs::file_size(*resolved, ec) > kMaxImageBytes) {
    reason = fmt::format("{} is larger than {} MiB", name, kMaxImageBytes >> 20);
    return std::nullopt;
  }
  try {
    // Decoded only if no larger than twice the expected size: a hostile header cannot make the
    // grader allocate gigabytes, and a wrong size still gets its numbers below.
    Image image = read_image(*resolved, 2 * std::max(ref.width, ref.height));
    if (image.width != ref.width || image.height != ref.height) {
      reason = fmt::format("{}: expected {}x{}, got {}x{}", name, ref.width, ref.height, image.width, image.height);
      return std::nullopt;
    }
    return image;
  } catch (const std::exception& e) {
    std::string what = e.what();
    const std::string prefix = resolved->string() + ": ";
    if (what.rfind(prefix, 0) == 0) what = what.substr(prefix.size());  // the grader's paths stay out of feedback
    reason = fmt::format("{} could not be read as a {}x{} image: {}", name, ref.width, ref.height, what);
    return std::nullopt;
  }
}

// Compares the student's image with the reference and scores it; writes the pictures the
// feedback shows under `work`.
// An 8-bit image (read_image knows a PNG or JPEG by its contents) meets the reference's preview,
// an EXR the linear EXR.
void judge(const GradeTask& task, const Image& student, const Reference& ref, const fs::path& work,
           int compare_threads, TaskGrade& grade) {
  const bool ldr = student.display_referred;
  CompareSettings settings = task.score.compare;
  settings.threads = compare_threads;
  grade.result = compare_images(ldr ? *ref.preview_image : *ref.exr_image, student, settings);
  grade.compared = true;
  grade.points = score_points(task.score, grade.result, task.points, grade.reason);
  fs::create_directories(work);
  grade.student_png = work / (task.name + ".student.png");
  grade.reference_png = ref.display;
  write_png_image(to_display(student), grade.student_png);
  if (grade.result.difference.pixel_count() > 0) {
    grade.difference_png = work / (task.name + ".difference.png");
    write_png_image(grade.result.difference, grade.difference_png);
  }
}

TaskGrade grade_task(const GradeTask& task, const fs::path& folder, const Reference& ref, const fs::path& work,
                     bool folder_is_link, int compare_threads, bool keep_work) {
  const auto start = Clock::now();
  TaskGrade grade;
  grade.task = task.name;
  grade.max_points = task.points;
  grade.visibility = task.visibility;
  try {
    if (folder_is_link) {
      grade.reason = "the submission folder is a link; nothing in it was read";
    } else if (task.file) {
      if (auto image = read_student_image(folder, *task.file, ref, grade.reason)) {
        judge(task, *image, ref, work, compare_threads, grade);
      }
    } else {
      const ProgramRun run = run_student_program(*task.run, folder, ref.job_folder, ref.job_file, work / task.name);
      grade.program_output = run.output;
      if (!run.image_file) {
        grade.reason = run.reason;
      } else if (auto image = read_student_image(run.image_file->parent_path(), run.image_file->filename(), ref, grade.reason)) {
        judge(task, *image, ref, work, compare_threads, grade);
      }
    }
  } catch (const std::exception& e) {
    grade.points = 0.0;
    grade.reason = fmt::format("could not be graded: {}", e.what());
  }
  // A class of 40 kept 40 copies of up to 1 GiB (issue #32): the copy goes once its image is read.
  if (task.run && !keep_work) {
    std::error_code ignored;
    fs::remove_all(work / task.name, ignored);
  }
  grade.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return grade;
}

// Students graded side by side each compare on one thread; one alone uses them all.
StudentGrade grade_one(const Rubric& rubric, const std::map<fs::path, Reference>& references, const fs::path& folder,
                       const std::string& id, const GradeOptions& options, int compare_threads) {
  const auto start = Clock::now();
  StudentGrade student;
  student.student = id;
  std::error_code ec;
  const bool is_link = fs::is_symlink(fs::symlink_status(folder, ec));
  const fs::path work = options.output_dir / "work" / id;
  for (const GradeTask& task : rubric.tasks) {
    student.tasks.push_back(
        grade_task(task, folder, references.at(task.job), work, is_link, compare_threads, options.keep_work));
  }
  student.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return student;
}

}  // namespace

double score_points(const ScoreRule& rule, const CompareResult& result, double max_points, std::string& reason) {
  if (!rule.full) {
    const bool passed = result.verdict != Verdict::fail;
    reason = fmt::format("{}: {}, {}", to_string(result.verdict), result.summary,
                         passed ? fmt::format("all {} points", points_text(max_points)) : std::string("0 points"));
    return passed ? max_points : 0.0;
  }
  const std::string figure = rule.figure();
  const double value = result.figure(figure), full = *rule.full, zero = *rule.zero;
  double fraction = (value - zero) / (full - zero);
  if (!std::isfinite(fraction)) fraction = std::isinf(value) && ((value > 0) == (full > zero)) ? 1.0 : 0.0;
  fraction = std::clamp(fraction, 0.0, 1.0);
  if (std::isnan(value)) {
    reason = fmt::format("{}: {}, 0 points", to_string(result.verdict), result.summary);
    return 0.0;
  }
  const double points = fraction * max_points;
  reason = fmt::format("{} {:.4g}: {:g} earns all {} points, {:g} none", figure_label(figure), value, full,
                       points_text(max_points), zero);
  return points;
}

StudentGrade grade_submission(const Rubric& rubric, const fs::path& folder, const std::string& id,
                              const GradeOptions& options) {
  return grade_one(rubric, render_references(rubric, options), folder, id, options, 0);
}

ClassGrades grade_class(const Rubric& rubric, const fs::path& submissions, const GradeOptions& options,
                        const GradeEvents& events) {
  std::error_code ec;
  if (!fs::is_directory(submissions, ec)) {
    throw InputError(fmt::format("{}: not a folder (SUBMISSIONS holds one folder per student)", submissions.string()));
  }
  std::vector<std::string> ids;
  for (const fs::directory_entry& entry : fs::directory_iterator(submissions)) {
    // Every folder is a student, a link to one too (graded as nothing read); files are not.
    if (entry.is_directory(ec) || fs::is_symlink(entry.symlink_status(ec))) ids.push_back(entry.path().filename().string());
  }
  std::sort(ids.begin(), ids.end());
  const std::map<fs::path, Reference> references = render_references(rubric, options);

  ClassGrades grades;
  grades.rubric = &rubric;
  grades.students.resize(ids.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex events_mutex;
  const int jobs = options.jobs > 0 ? options.jobs : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int compare_threads = jobs > 1 ? 1 : 0;
  const auto work = [&] {
    for (std::size_t i; (i = next++) < ids.size();) {
      grades.students[i] = grade_one(rubric, references, submissions / ids[i], ids[i], options, compare_threads);
      std::lock_guard lock(events_mutex);
      if (events.graded) events.graded(grades.students[i]);
      if (events.progress) events.progress(++done, ids.size());
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < std::min<int>(jobs, static_cast<int>(ids.size())); ++t) threads.emplace_back(work);
  work();
  for (std::thread& t : threads) t.join();
  return grades;
}

}  // namespace farm
