// `farm validate` and the validation `farm render` runs for validate.embree_rays, through the
// real binary.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/farm_cli_fixture.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::run_command;
using test::shell_quote;

using test::kSource;

class FarmValidateCli : public test::FarmCliFixture {};

TEST_F(FarmValidateCli, CornellNaiveAgreesWithEmbree) {
  const auto r = run_command(farm("validate " + shell_quote((kSource / "jobs/cornell.json").string()) +
                                  " --rays 2000 --accel naive"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("embree validation: 2000 rays, 0 hit/miss"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("naive"), std::string::npos) << r.output;
}

TEST_F(FarmValidateCli, DefaultsToTheJobsAccelAndRayCount) {
  std::ofstream(dir_ / "m.obj") << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n";
  const fs::path job = dir_.write("j.json", R"({"version": 1, "name": "quad",
      "scene": {"objects": [{"file": "m.obj", "rotate": {"axis": [0, 1, 0], "degrees": 30}}],
                "camera": {"position": [0, 0, 3], "target": [0, 0, 0]}},
      "render": {"width": 40, "height": 30, "accel": "bvh-median"},
      "validate": {"embree_rays": 3000}})");
  const auto r = run_command(farm("validate " + shell_quote(job.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("bvh-median vs embree on 3000 rays"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("embree validation: 3000 rays"), std::string::npos) << r.output;
}

TEST_F(FarmValidateCli, HelpDocumentsTheExitCodes) {
  const auto r = run_command(farm("validate --help"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Exit codes: 0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--rays"), std::string::npos) << r.output;
  EXPECT_NE(run_command(farm("--help")).output.find("validate"), std::string::npos);
}

TEST_F(FarmValidateCli, EmbreeAsOursOrAMissingJobIsBadInput) {
  const std::string cornell = shell_quote((kSource / "jobs/cornell.json").string());
  const auto embree = run_command(farm("validate " + cornell + " --accel embree"));
  EXPECT_EQ(embree.exit_code, 2) << embree.output;
  EXPECT_NE(embree.output.find("--accel"), std::string::npos) << embree.output;
  const auto missing = run_command(farm("validate " + shell_quote((dir_ / "nope.json").string())));
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  const auto zero = run_command(farm("validate " + cornell + " --rays 0"));
  EXPECT_EQ(zero.exit_code, 2) << zero.output;
}

TEST_F(FarmValidateCli, RenderWithEmbreeRaysPrintsTheValidationSummary) {
  fs::copy_file(kSource / "jobs/assets/cornell_box.obj", dir_ / "cornell_box.obj");
  fs::copy_file(kSource / "jobs/assets/cornell_box.mtl", dir_ / "cornell_box.mtl");
  const fs::path job = dir_.write("r.json", R"({"version": 1, "name": "cornell-check",
      "scene": {"objects": [{"file": "cornell_box.obj"}],
                "camera": {"position": [0, 0, 3.9], "target": [0, 0, 0], "fov_y": 40}},
      "render": {"width": 24, "height": 24, "accel": "embree"},
      "output": {"image": ")" + (dir_ / "r.exr").string() + R"(", "preview": ""},
      "validate": {"embree_rays": 1000}})");
  const auto r = run_command(farm("render " + shell_quote(job.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // A job rendered with Embree is checked with our default BVH.
  EXPECT_NE(r.output.find("embree validation: 1000 rays, 0 hit/miss"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bvh vs embree"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace farm
