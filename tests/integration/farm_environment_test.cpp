// Environment-lit jobs through a real farm: `farm submit --wait` uploads the job's map with its
// model (the map is a file the job names, not one a model names) and the images a glTF names
// (jobs/showcase.json: seven PNGs), a worker decodes them, and the image is the one `farm render`
// makes, bit for bit, for each engine.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "renderer/image/exr_io.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

TEST(FarmEnvironment, SubmittedJobsSendTheirMapAndTexturesAndMatchFarmRenderBitForBit) {
  test::TempDir dir;
  // The example job and its files, away from the checkout; its outputs named absolutely.
  fs::create_directories(dir / "job");
  fs::copy(fs::path(FARM_SOURCE_DIR) / "jobs/assets", dir / "job/assets", fs::copy_options::recursive);
  test::LocalFarm farm = test::start_local_farm(dir / "farm", 1);
  ASSERT_TRUE(farm.problem.empty()) << farm.problem;
  const std::pair<const char*, const char*> runs[] = {
      {"environment.json", "raster"}, {"environment.json", "path"}, {"showcase.json", "raster"}, {"showcase.json", "path"}};
  for (const auto& [example, engine] : runs) {
    SCOPED_TRACE(std::string(example) + ", " + engine);
    nlohmann::json job = nlohmann::json::parse(test::read_file(fs::path(FARM_SOURCE_DIR) / "jobs" / example));
    const auto write_job = [&](const std::string& name) {
      job["render"] = {{"engine", engine}, {"width", 48}, {"height", 36}, {"spp", 4}, {"max_depth", -1}};
      job["output"] = {{"image", (dir / (name + ".exr")).string()}, {"preview", ""}};
      return dir.write("job/" + name + ".json", job.dump());
    };
    const fs::path rendered = write_job("rendered"), submitted = write_job("submitted");
    const test::CommandResult render =
        test::run_command(test::farm_command("render " + test::shell_quote(rendered.string()) + " --quiet"));
    ASSERT_EQ(render.exit_code, 0) << render.output;
    const test::CommandResult submit = test::run_command(test::farm_command(
        "submit " + test::shell_quote(submitted.string()) + " --wait --scheduler " + farm.address()));
    ASSERT_EQ(submit.exit_code, 0) << submit.output;
    const TileBuffer a = read_exr(dir / "rendered.exr"), b = read_exr(dir / "submitted.exr");
    ASSERT_EQ(a.rect().width(), 48);
    ASSERT_EQ(b.rect().width(), 48);
    int sky = 0;
    for (int y = 0; y < 36; ++y)
      for (int x = 0; x < 48; ++x) {
        ASSERT_EQ(std::memcmp(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)), 0) << "at " << x << "," << y;
        // The sky is the map's blue, not the default grey background: the map was read.
        const glm::vec4 p = a.rgba(x, y);
        if (p.w == 0.0f && p.z > p.x * 1.1f) ++sky;
      }
    EXPECT_GT(sky, 48) << "the map's sky should fill the top rows";
  }
}

}  // namespace
}  // namespace farm
