// One valid job never freezes the farm (issue #32): a light of intensity 3e38, which the job
// rules accepted, made +inf pixels on the farm, and the result check quarantined every honest
// worker in turn while every other job waited. Now the job file refuses such a light naming its
// key and bound, and the brightest light it accepts, close to a wall, renders on a farm of two
// workers to the same bits as `farm render` (the engines hold radiance to one bound), next to an
// ordinary job, with no worker quarantined.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "renderer/image/exr_io.h"
#include "server/common/job_state.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

bool final_job(const v1::Job& j) { return is_final(j.state()); }

TEST(ExtremeLight, ARefusedLightNamesItsKeyAndTheBrightestAllowedRendersAsFarmRenderBesideAnOrdinaryJob) {
  test::TempDir dir;
  test::LocalFarm farm = test::start_local_farm(dir / "farm", 2, {"--float"});
  ASSERT_TRUE(farm.problem.empty()) << farm.problem;
  auto stub = test::scheduler_stub(farm.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  const auto job_with_light = [](double intensity) {
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("whitted", 48, 48, 1));
    job["scene"]["lights"] = {{{"position", {0.0, 0.0, 0.5}}, {"intensity", intensity}}};
    job["render"]["tile_size"] = 16;
    return job.dump();
  };

  v1::Job refused;
  const grpc::Status status =
      test::submit(*stub, test::make_job_spec(job_with_light(3e38), test::cornell_assets(), "cornell.json"), refused);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("scene.lights[0].intensity"), std::string::npos) << status.error_message();
  EXPECT_NE(status.error_message().find("<= 1000000000000000"), std::string::npos) << status.error_message();

  const std::string bright_text = job_with_light(1e15);
  v1::Job bright, ordinary;
  ASSERT_TRUE(test::submit(*stub, test::make_job_spec(bright_text, test::cornell_assets(), "cornell.json"), bright).ok());
  ASSERT_TRUE(test::submit(*stub, test::cornell_job_spec("raster", 48, 48, 1), ordinary).ok());
  for (const v1::Job& j : {bright, ordinary}) {
    const std::optional<v1::Job> done = test::wait_for_job(*stub, j.job_id(), final_job, 120s);
    ASSERT_TRUE(done) << farm.scheduler->process().output();
    EXPECT_EQ(done->state(), v1::JOB_STATE_SUCCEEDED) << done->failure_reason();
  }
  EXPECT_EQ(farm.scheduler->process().output().find("quarantined"), std::string::npos)
      << farm.scheduler->process().output();

  // The same bits as farm render, pixels at the bound and all.
  const fs::path fetched = dir / "farm.exr";
  ASSERT_TRUE(test::fetch_result(*stub, bright.job_id(), v1::RESULT_KIND_EXR, fetched).ok());
  fs::create_directories(dir / "local/assets");
  for (const auto& [path, file] : test::cornell_assets()) fs::copy_file(file, dir / "local" / path);
  std::ofstream(dir / "local/cornell.json") << bright_text;
  const test::CommandResult r = test::run_command(test::farm_command(
      "render " + (dir / "local/cornell.json").string() + " --float --quiet --preview none --out " +
      (dir / "local.exr").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const TileBuffer a = read_exr(fetched), b = read_exr(dir / "local.exr");
  ASSERT_EQ(a.rect(), b.rect());
  int at_bound = 0;
  for (int y = a.rect().y0; y < a.rect().y1; ++y) {
    for (int x = a.rect().x0; x < a.rect().x1; ++x) {
      ASSERT_EQ(std::memcmp(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)), 0) << x << ", " << y;
      at_bound += a.rgba(x, y).x == 1e15f;
    }
  }
  EXPECT_GT(at_bound, 0) << "no pixel reached the radiance bound: the light was not extreme here";
}

}  // namespace
}  // namespace farm
