// `farm grade` on a synthetic class, as course staff run it: a perfect submission, a noisy one,
// one shifted by 2 px, one 10% darker, a missing file, the wrong size, a corrupt PNG, a link out
// of the student's folder, a folder where the image should be, a 30000x30000 header, and two
// identical submissions. Every student gets the points the rubric says, a CSV row, a feedback
// page and a Gradescope results.json; the identical pair is in similar.csv; nothing outside a
// submission is read; and the same class graded through a scheduler gives the same CSV.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include "renderer/compare/compare.h"
#include "renderer/compare/image.h"
#include "server/grade/grade_rubric.h"
#include "server/grade/grade_runner.h"
#include "tests/support/background_process.h"
#include "tests/support/image_pairs.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

void write_bytes(const fs::path& file, const std::string& bytes) {
  fs::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary) << bytes;
}

// PNG's CRC-32 (ISO 3309), for a header patched to claim another size.
std::uint32_t crc32(const std::string& bytes) {
  std::uint32_t crc = 0xffffffffu;
  for (unsigned char b : bytes) {
    crc ^= b;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

// A valid PNG whose header says 30000 x 30000 (its data is the small image's): a reader that
// trusted the header would allocate gigabytes.
std::string huge_png(const std::string& small) {
  std::string png = small;
  const auto put = [&](std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) png[at + static_cast<std::size_t>(i)] = static_cast<char>((v >> (24 - 8 * i)) & 0xff);
  };
  put(16, 30000);  // IHDR width, after the signature (8), length (4) and type (4)
  put(20, 30000);
  put(29, crc32(png.substr(12, 17)));  // the CRC over type and data
  return png;
}

Image variant(const Image& reference, double noise, int shift, float gain, std::uint32_t seed) {
  Image out = reference;
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, static_cast<float>(noise > 0 ? noise : 1.0));
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c) {
        float v = reference.at(std::clamp(x - shift, 0, out.width - 1), y, c) * gain;
        if (noise > 0) v += n(rng);
        out.at(x, y, c) = std::clamp(v, 0.0f, 1.0f);
      }
  return out;
}

class FarmGradeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string jobs = std::string(FARM_SOURCE_DIR) + "/jobs";
    job_ = dir_.write("rubric/cornell.json", fmt::format(R"({{
  "version": 1, "name": "cornell",
  "scene": {{ "objects": [ {{ "file": "{}/assets/cornell_box.obj" }} ], "camera": {{ "position": [0, 1, 3.4], "target": [0, 1, 0], "fov_y": 40 }} }},
  "render": {{ "engine": "raster", "width": 96, "height": 72, "spp": 4 }} }})", jobs));
    rubric_ = dir_.write("rubric/rubric.json", fmt::format(R"({{
  "version": 1, "name": "lab", "asset_root": "{}",
  "tasks": [
    {{ "name": "image", "points": 60, "job": "cornell.json", "file": "cornell.png",
      "score": {{ "metric": "flip", "full": 0.02, "zero": 0.2 }} }},
    {{ "name": "edges", "points": 40, "job": "cornell.json", "file": "cornell.png",
      "score": {{ "metric": "threshold", "fail": 0.1, "fail_percent": 2 }}, "visibility": "hidden" }} ] }})", jobs));
    // The reference as the grader renders it: this job through `farm render`.
    const test::CommandResult r = test::run_command(test::farm_command(
        fmt::format("render {} --asset-root {} --out {} --preview {} --quiet 2>&1", test::shell_quote(job_.string()),
                    test::shell_quote(jobs),
                    test::shell_quote((dir_ / "ref.exr").string()), test::shell_quote((dir_ / "ref.png").string()))));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    reference_ = read_image(dir_ / "ref.png");

    const fs::path subs = dir_ / "subs";
    const auto student = [&](const std::string& id, const Image& image) { write_png_image(image, subs / id / "cornell.png"); };
    student("perfect", reference_);
    student("noisy", variant(reference_, 0.03, 0, 1.0f, 1));
    student("shifted", variant(reference_, 0.0, 2, 1.0f, 0));
    student("darker", variant(reference_, 0.0, 0, 0.9f, 0));
    student("twin-a", variant(reference_, 0.05, 0, 1.0f, 7));
    student("twin-b", variant(reference_, 0.05, 0, 1.0f, 7));
    fs::create_directories(subs / "missing");
    write_bytes(subs / "missing" / "readme.txt", "forgot it");
    student("wrongsize", test::synthetic_reference(80, 60));
    const std::string good = test::read_file(subs / "perfect" / "cornell.png");
    write_bytes(subs / "corrupt" / "cornell.png", good.substr(0, good.size() / 3));
    write_bytes(subs / "huge" / "cornell.png", huge_png(good));
    // A link out of the folder, to a perfect image: if it were read, it would score full marks.
    write_bytes(dir_ / "elsewhere" / "cornell.png", good);
    fs::create_directories(subs / "escape");
    fs::create_symlink(dir_ / "elsewhere" / "cornell.png", subs / "escape" / "cornell.png");
    fs::create_directories(subs / "folder" / "cornell.png");
  }

  test::CommandResult grade(const std::string& out, const std::string& flags = "") {
    return test::run_command(test::farm_command(fmt::format("grade {} {} --out {} {} 2>&1", test::shell_quote(rubric_.string()),
                                                            test::shell_quote((dir_ / "subs").string()),
                                                            test::shell_quote((dir_ / out).string()), flags)));
  }

  // The points our own metrics give an image: what the grader must award.
  double expected_points(const Image& image, Metric metric) {
    CompareSettings s;
    s.metric = metric;
    if (metric == Metric::flip) {
      const double mean = compare_images(reference_, image, s).figure("flip_mean");
      return 60.0 * std::clamp((mean - 0.2) / (0.02 - 0.2), 0.0, 1.0);
    }
    s.fail = 0.1;
    s.fail_percent = 2;
    return compare_images(reference_, image, s).verdict == Verdict::fail ? 0.0 : 40.0;
  }

  test::TempDir dir_;
  fs::path job_, rubric_;
  Image reference_;
};

// grades.csv as rows of cells by student (no quoting needed for these ids).
std::map<std::string, std::vector<std::string>> csv_rows(const fs::path& file) {
  std::map<std::string, std::vector<std::string>> rows;
  std::istringstream in(test::read_file(file));
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();  // RFC 4180 ends records with CRLF
    std::vector<std::string> cells;
    std::istringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    if (!cells.empty()) rows[cells[0]] = cells;
  }
  return rows;
}

TEST_F(FarmGradeTest, EveryStudentGetsTheRubricsPointsAReasonAFeedbackPageAndResults) {
  const test::CommandResult run = grade("grades");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto rows = csv_rows(dir_ / "grades/grades.csv");
  ASSERT_EQ(rows.at("student"), (std::vector<std::string>{"student", "image", "edges", "total", "maximum"}));
  const auto points = [&](const std::string& id, std::size_t column) { return std::stod(rows.at(id).at(column)); };
  EXPECT_EQ(points("perfect", 1), 60.0);
  EXPECT_EQ(points("perfect", 2), 40.0);
  EXPECT_EQ(points("perfect", 3), 100.0);
  EXPECT_EQ(points("perfect", 4), 100.0);
  // The degraded images: the points their figures earn, to the CSV's two decimals.
  for (const auto& [id, image] : std::map<std::string, Image>{{"noisy", variant(reference_, 0.03, 0, 1.0f, 1)},
                                                              {"shifted", variant(reference_, 0.0, 2, 1.0f, 0)},
                                                              {"darker", variant(reference_, 0.0, 0, 0.9f, 0)}}) {
    // Through a PNG, as the grader reads it.
    write_png_image(image, dir_ / "check.png");
    const Image stored = read_image(dir_ / "check.png");
    EXPECT_NEAR(points(id, 1), expected_points(stored, Metric::flip), 0.006) << id;
    EXPECT_EQ(points(id, 2), expected_points(stored, Metric::threshold)) << id;
    EXPECT_LT(points(id, 3), 100.0) << id;
  }
  for (const char* id : {"missing", "wrongsize", "corrupt", "huge", "escape", "folder"}) {
    EXPECT_EQ(points(id, 3), 0.0) << id;
  }
  EXPECT_EQ(rows.size(), 13u) << "a header and 12 students";

  // The reasons, in words a student understands, on their feedback pages.
  const auto page = [&](const std::string& id) { return test::read_file(dir_ / "grades/feedback" / id / "index.html"); };
  EXPECT_NE(page("missing").find("cornell.png is missing from the submission"), std::string::npos);
  EXPECT_NE(page("wrongsize").find("cornell.png: expected 96x72, got 80x60"), std::string::npos);
  EXPECT_NE(page("corrupt").find("cornell.png could not be read"), std::string::npos);
  EXPECT_NE(page("huge").find("cornell.png could not be read"), std::string::npos);
  EXPECT_NE(page("escape").find("outside the submission folder"), std::string::npos);
  EXPECT_NE(page("folder").find("cornell.png is a folder"), std::string::npos);
  EXPECT_NE(page("noisy").find("FLIP mean"), std::string::npos);
  EXPECT_NE(page("noisy").find("0.02 earns all 60 points, 0.2 none"), std::string::npos);
  EXPECT_EQ(page("escape").find(dir_.path().string()), std::string::npos) << "the grader's paths stay out of feedback";

  // Gradescope results for everyone, with each task's score.
  const nlohmann::json results = nlohmann::json::parse(test::read_file(dir_ / "grades/gradescope/perfect/results.json"));
  EXPECT_EQ(results["score"].get<double>(), 100.0);
  ASSERT_EQ(results["tests"].size(), 2u);
  EXPECT_EQ(results["tests"][1]["name"], "edges");
  EXPECT_EQ(results["tests"][1]["visibility"], "hidden");
  std::string files;
  for (const auto& [id, row] : rows) {
    if (id == "student") continue;
    EXPECT_TRUE(fs::exists(dir_ / "grades/gradescope" / id / "results.json")) << id;
    files += fmt::format(" {}", test::shell_quote((dir_ / "grades/gradescope" / id / "results.json").string()));
  }
  // Every one valid under the schema written from Gradescope's specification.
  const test::CommandResult valid = test::run_command(fmt::format(
      "{} {}/tests/python/validate_json_schema.py {}/tests/data/gradescope/results.schema.json{} 2>&1",
      test::shell_quote(FARM_TEST_PYTHON), FARM_SOURCE_DIR, FARM_SOURCE_DIR, files));
  EXPECT_EQ(valid.exit_code, 0) << valid.output;

  // The identical pair is flagged for a person to look at; the perfect student and the one who
  // linked to a copy of the reference are not (the link was never read).
  const std::string similar = test::read_file(dir_ / "grades/similar.csv");
  EXPECT_NE(similar.find("twin-a,twin-b"), std::string::npos) << similar;
  EXPECT_EQ(similar.find("escape"), std::string::npos) << similar;
  EXPECT_TRUE(fs::exists(dir_ / "grades/summary.html"));
}

TEST_F(FarmGradeTest, TheSameClassThroughASchedulerWithTwoWorkersGivesTheSameCsv) {
  ASSERT_EQ(grade("local").exit_code, 0);
  const test::LocalFarm loopback = test::start_local_farm(dir_.path(), 2);
  ASSERT_TRUE(loopback.problem.empty()) << loopback.problem;
  const test::CommandResult remote = grade("remote", "--scheduler " + test::shell_quote(loopback.address()));
  ASSERT_EQ(remote.exit_code, 0) << remote.output;
  EXPECT_EQ(test::read_file(dir_ / "remote/grades.csv"), test::read_file(dir_ / "local/grades.csv"));
}

TEST_F(FarmGradeTest, InsideGradescopeTheOneSubmissionIsGradedIntoResultsJson) {
  // Gradescope's layout: /autograder/submission in, /autograder/results/results.json out.
  const fs::path root = dir_ / "autograder";
  fs::create_directories(root / "results");
  fs::copy(dir_ / "subs" / "noisy", root / "submission", fs::copy_options::recursive);
  const test::CommandResult r = test::run_command(test::farm_command(
      fmt::format("grade {} --gradescope --gradescope-root {} 2>&1", test::shell_quote(rubric_.string()),
                  test::shell_quote(root.string()))));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json results = nlohmann::json::parse(test::read_file(root / "results" / "results.json"));
  const auto rows = [&] {
    EXPECT_EQ(grade("class").exit_code, 0);
    return csv_rows(dir_ / "class/grades.csv");
  }();
  EXPECT_NEAR(results["score"].get<double>(), std::stod(rows.at("noisy").at(3)), 0.006);
  EXPECT_EQ(results["tests"].size(), 2u);
}

TEST(FarmGradeRubric, BadRubricsExitTwoNamingTheJsonPath) {
  test::TempDir dir;
  const std::string job = std::string(FARM_SOURCE_DIR) + "/jobs/cornell.json";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"version": 1, "name": "r", "tasks": [{"name": "a", "points": 10, "job": "JOB", "score": {"metric": "flip"}}]})",
       "tasks[0]: a task needs either \"file\""},
      {R"({"version": 1, "name": "r", "tasks": [{"name": "a", "points": 10, "job": "JOB", "file": "../x.png", "score": {"metric": "flip"}}]})",
       "tasks[0].file: '../x.png' must be a path inside the student's folder"},
      {R"({"version": 1, "name": "r", "tasks": [{"name": "a", "points": 10, "job": "JOB", "file": "x.png", "score": {"metric": "flip", "full": 0.1}}]})",
       "tasks[0].score: give both full and zero"},
      {R"({"version": 1, "name": "r", "tasks": [{"name": "a", "points": 0, "job": "JOB", "file": "x.png", "score": {"metric": "flip"}}]})",
       "tasks[0].points"},
      {R"({"version": 1, "name": "r", "tasks": [{"name": "a", "points": 5, "job": "JOB", "file": "x.png", "score": {"metric": "flip"}, "visibility": "secret"}]})",
       "tasks[0].visibility: unknown visibility 'secret'"},
      {R"({"version": 1, "name": "r", "tasks": [{"name": "a", "points": 5, "job": "JOB", "run": {"command": []}, "score": {"metric": "psnr"}}]})",
       "tasks[0].run.command: a command needs at least the program to run"},
  };
  const fs::path good = dir.write("good.json", R"({"version": 1, "name": "r", "tasks": [{"name": "a", "points": 5, "job": ")" +
                                                     job + R"(", "file": "x.png", "score": {"metric": "flip"}}]})");
  const test::CommandResult missing = test::run_command(test::farm_command(
      fmt::format("grade {} {} 2>&1", test::shell_quote(good.string()), test::shell_quote((dir / "nowhere").string()))));
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("nowhere: not a folder"), std::string::npos) << missing.output;
  for (const auto& [text, message] : cases) {
    std::string rubric = text;
    rubric.replace(rubric.find("JOB"), 3, job);
    const fs::path file = dir.write("rubric.json", rubric);
    const test::CommandResult r = test::run_command(
        test::farm_command(fmt::format("grade {} {} 2>&1", test::shell_quote(file.string()), test::shell_quote(dir.path().string()))));
    EXPECT_EQ(r.exit_code, 2) << text << "\n" << r.output;
    EXPECT_NE(r.output.find(file.string() + ": " + message), std::string::npos) << text << "\n" << r.output;
  }
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// A `run` task over a class of hostile programs: each is stopped or refused with its reason and
// scores 0, and the one honest program (which copies its answer to {output}) is still graded.
TEST_F(FarmGradeTest, HostileProgramsScoreZeroWithTheirReasonAndTheRestOfTheClassIsGraded) {
  const std::string jobs = std::string(FARM_SOURCE_DIR) + "/jobs";
  const fs::path rubric = dir_.write("rubric/run.json", fmt::format(R"({{
  "version": 1, "name": "lab-run", "asset_root": "{}",
  "tasks": [ {{ "name": "program", "points": 10, "job": "cornell.json",
    "run": {{ "command": ["sh", "render.sh", "{{job}}", "{{output}}"], "build": ["sh", "build.sh"],
             "time_limit_s": 3, "memory_mib": 256 }},
    "score": {{ "metric": "psnr", "full": 40, "zero": 20 }} }} ] }})", jobs));
  const fs::path subs = dir_ / "runs";
  const std::string answer = test::read_file(dir_ / "subs" / "perfect" / "cornell.png");
  const std::map<std::string, std::string> programs = {
      {"honest", "test -f \"$1\" && cp answer.png \"$2\""},
      {"loop", "while true; do :; done"},
      {"bomb", "exec bash -c 'while :; do sleep 5 & done'"},  // bash retries failed forks
      {"memory", "python3 -c 'x = bytearray(10 * 2**30)'"},
      {"disk", "head -c 1073741824 /dev/zero > big.bin"},
      {"network", "python3 -c 'import socket; socket.create_connection((\"1.1.1.1\", 80), timeout=1)' && cp answer.png \"$2\""},
      {"snoop", "cp ../honest/answer.png \"$2\" || cp /root/answer.png \"$2\""},
      {"nothing", "true"},
      {"garbage", "echo 'not a picture' > \"$2\""},
  };
  for (const auto& [id, script] : programs) {
    write_bytes(subs / id / "render.sh", script + "\n");
    write_bytes(subs / id / "build.sh", "echo building\n");
    write_bytes(subs / id / "answer.png", answer);
  }
  write_bytes(subs / "broken-build" / "build.sh", "echo 'error: missing semicolon' >&2; exit 2\n");
  write_bytes(subs / "broken-build" / "render.sh", "cp answer.png \"$2\"\n");
  write_bytes(subs / "broken-build" / "answer.png", answer);

  const test::CommandResult run = test::run_command(test::farm_command(
      fmt::format("grade {} {} --out {} 2>&1", test::shell_quote(rubric.string()), test::shell_quote(subs.string()),
                  test::shell_quote((dir_ / "run-grades").string()))));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto rows = csv_rows(dir_ / "run-grades/grades.csv");
  EXPECT_EQ(std::stod(rows.at("honest").at(1)), 10.0) << run.output;
  const auto page = [&](const std::string& id) { return test::read_file(dir_ / "run-grades/feedback" / id / "index.html"); };
  const std::map<std::string, std::string> reasons = {
      {"loop", " time"} /* its wall or CPU time, whichever limit it meets first */, {"bomb", "processes"},          {"memory", "exited with code 1"},
      {"disk", "larger than"},        {"network", "exited with code"}, {"snoop", "exited with code"},
      {"nothing", "wrote nothing"},   {"garbage", "could not be read"}, {"broken-build", "the build failed"}};
  for (const auto& [id, words] : reasons) {
    EXPECT_EQ(std::stod(rows.at(id).at(1)), 0.0) << id;
    EXPECT_NE(page(id).find(words), std::string::npos) << id << " should say '" << words << "':\n" << page(id);
  }
  EXPECT_NE(page("memory").find("MemoryError"), std::string::npos) << "the program's output is on its page";
  EXPECT_NE(page("broken-build").find("missing semicolon"), std::string::npos);
  // Each program's work copy (the disk filler's held 1 GiB) is gone once graded; the picture its
  // feedback shows stays.
  for (const auto& [id, script] : programs) EXPECT_FALSE(fs::exists(dir_ / "run-grades/work" / id / "program")) << id;
  EXPECT_TRUE(fs::exists(dir_ / "run-grades/work/honest/program.student.png"));

  // With --keep-work a copy stays to look into.
  const test::CommandResult kept = test::run_command(test::farm_command(
      fmt::format("grade {} {} --out {} --keep-work 2>&1", test::shell_quote(rubric.string()),
                  test::shell_quote(subs.string()), test::shell_quote((dir_ / "kept-grades").string()))));
  ASSERT_EQ(kept.exit_code, 0) << kept.output;
  EXPECT_TRUE(fs::exists(dir_ / "kept-grades/work/honest/program/work/render.sh"));
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

// The lab's rubric as shipped: it reads, its jobs exist, its asset root holds the shared cow.
TEST(FarmGradeRubric, TheLabsRubricLoadsWithItsThreeImageTasks) {
  const Rubric rubric = load_rubric(fs::path(FARM_SOURCE_DIR) / "jobs/grade/dandelion/rubric.json");
  EXPECT_EQ(rubric.name, "dandelion");
  ASSERT_EQ(rubric.tasks.size(), 3u);
  EXPECT_EQ(rubric.max_points(), 100.0);
  for (const GradeTask& task : rubric.tasks) {
    EXPECT_TRUE(task.file.has_value()) << task.name;
    EXPECT_EQ(task.score.compare.metric, Metric::flip) << task.name;
  }
  EXPECT_TRUE(fs::exists(rubric.asset_root / "shared/assets/dae/cow.dae")) << rubric.asset_root;
}

}  // namespace
}  // namespace farm
