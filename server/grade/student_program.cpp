#include "server/grade/student_program.h"

#include <fmt/format.h>

#include "server/grade/sandbox.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr std::uintmax_t kMaxCopyBytes = 256ull << 20;
constexpr std::size_t kMaxCopyFiles = 20000;
constexpr std::size_t kMaxOutputBytes = 16 * 1024;  // of each step, for the feedback page

// Copies the plain files and folders of `from` into `to`; links (which could lead anywhere),
// devices and FIFOs are left out. Returns false when the submission is too large to copy.
bool copy_submission(const fs::path& from, const fs::path& to, std::string& reason) {
  std::uintmax_t bytes = 0;
  std::size_t files = 0;
  std::error_code ec;
  fs::create_directories(to);
  for (auto it = fs::recursive_directory_iterator(from, fs::directory_options::none, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const fs::file_status status = it->symlink_status(ec);
    const fs::path target = to / it->path().lexically_relative(from);
    if (fs::is_directory(status)) {
      fs::create_directories(target, ec);
    } else if (fs::is_regular_file(status)) {
      bytes += it->file_size(ec);
      if (++files > kMaxCopyFiles || bytes > kMaxCopyBytes) {
        reason = fmt::format("the submission is larger than {} files or {} MiB", kMaxCopyFiles, kMaxCopyBytes >> 20);
        return false;
      }
      fs::copy_file(it->path(), target, fs::copy_options::overwrite_existing, ec);
    }
  }
  return true;
}

std::string substitute(std::string arg, const std::string& job, const std::string& output) {
  for (const auto& [key, value] : {std::pair<std::string, std::string>{"{job}", job}, {"{output}", output}}) {
    for (std::size_t at; (at = arg.find(key)) != std::string::npos;) arg.replace(at, key.size(), value);
  }
  return arg;
}

}  // namespace

ProgramRun run_student_program(const RunSpec& spec, const fs::path& submission, const fs::path& job_folder,
                               const fs::path& job_file, const fs::path& work_dir) {
  ProgramRun out;
  std::error_code ec;
  fs::remove_all(work_dir, ec);
  const fs::path work = work_dir / "work";
  if (!copy_submission(submission, work, out.reason)) return out;

  SandboxRun run;
  run.workdir = "/work";
  run.mounts = {{work, "/work", true}, {job_folder, "/job", false}};
  run.limits.wall_seconds = spec.time_limit_s;
  run.limits.cpu_seconds = spec.time_limit_s;
  run.limits.memory_mib = static_cast<std::uint64_t>(spec.memory_mib);
  run.limits.output_bytes = kMaxOutputBytes;
  const std::string output_name = "output." + spec.output_extension;
  const std::string job_inside = (fs::path("/job") / job_file.lexically_relative(job_folder)).generic_string();

  if (!spec.build.empty()) {
    run.argv = spec.build;
    const SandboxResult built = run_sandboxed(run);
    out.output += "$ build\n" + built.output;
    if (!built.ok()) {
      out.reason = "the build failed: " + built.reason(run.limits);
      return out;
    }
  }
  run.argv.clear();
  for (const std::string& arg : spec.command) run.argv.push_back(substitute(arg, job_inside, "/work/" + output_name));
  const SandboxResult ran = run_sandboxed(run);
  out.output += "$ run\n" + ran.output;
  if (!ran.ok()) {
    out.reason = "the program " + ran.reason(run.limits);
    return out;
  }
  const fs::path image = work / output_name;
  if (!fs::exists(fs::symlink_status(image, ec))) {
    out.reason = fmt::format("the program exited normally but wrote nothing at {{output}} ({})", output_name);
    return out;
  }
  out.image_file = image;
  return out;
}

}  // namespace farm
