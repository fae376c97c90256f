// Drives the real `farm` binary as a user would and checks exit codes, messages and files.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>

#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include "renderer/geometry/traversal_isa.h"
#include "renderer/image/exr_io.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::run_command;
using test::shell_quote;

using test::kSource;

class FarmCliTest : public test::FarmCliFixture {};

TEST_F(FarmCliTest, RenderCornellJobWritesExrWithAovsAndPreview) {
  const fs::path exr = dir_ / "c.exr", png = dir_ / "c.png";
  const auto r = run_command(farm("render " + shell_quote((kSource / "jobs/cornell.json").string()) +
                                  " --width 96 --height 96 --out " + shell_quote(exr.string()) +
                                  " --preview " + shell_quote(png.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(exr.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("time:"), std::string::npos) << r.output;
  ASSERT_TRUE(fs::exists(png));
  const TileBuffer image = read_exr(exr);
  EXPECT_EQ(image.rect(), (Rect{0, 0, 96, 96}));
  EXPECT_TRUE(image.aovs().depth && image.aovs().normal && image.aovs().albedo);
  // The room fills the middle of the frame: covered, lit, at a finite depth.
  EXPECT_EQ(image.rgba(48, 48).w, 1.0f);
  EXPECT_GT(image.rgba(48, 48).x, 0.0f);
  EXPECT_TRUE(std::isfinite(image.depth(48, 48)));
}

TEST_F(FarmCliTest, ThreadsAndTileSizeDoNotChangeASingleBit) {
  const std::string job = shell_quote((kSource / "jobs/torus.json").string());
  const fs::path a = dir_ / "a.exr", b = dir_ / "b.exr";
  const std::string common = " --width 160 --height 100 --float --preview none";
  ASSERT_EQ(run_command(farm("render " + job + common + " --threads 1 --tile-size 7 --out " +
                             shell_quote(a.string()))).exit_code, 0);
  ASSERT_EQ(run_command(farm("render " + job + common + " --threads 2 --tile-size 64 --out " +
                             shell_quote(b.string()))).exit_code, 0);
  const TileBuffer ia = read_exr(a), ib = read_exr(b);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 160; ++x)
      ASSERT_EQ(std::memcmp(&ia.rgba(x, y), &ib.rgba(x, y), sizeof(glm::vec4)), 0) << x << "," << y;
}

// `farm render` ends its process once its files are written, without taking the embedded farm
// apart (exit_abandoning_calls): what it printed still arrives whole through a pipe, and the
// farm's scratch folder under TMPDIR is gone.
TEST_F(FarmCliTest, RenderEndsWithItsSummaryFlushedAndNoScratchFolderLeft) {
  const fs::path tmp = dir_ / "tmp";
  fs::create_directories(tmp);
  const fs::path out = dir_ / "o.exr";
  const auto r = run_command("TMPDIR=" + shell_quote(tmp.string()) + " " +
                             farm("render " + shell_quote((kSource / "jobs/cornell.json").string()) +
                                  " --width 64 --height 48 --quiet --preview none --out " + shell_quote(out.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote " + out.string() + " ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\ntime: "), std::string::npos) << r.output;  // the summary's last line
  EXPECT_TRUE(fs::exists(out));
  std::string left;
  for (const auto& entry : fs::directory_iterator(tmp)) left += entry.path().string() + " ";
  EXPECT_TRUE(left.empty()) << "left behind: " << left;
}

TEST_F(FarmCliTest, BadJobExitsWith2AndNamesTheJsonPath) {
  std::ofstream(dir_ / "m.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const fs::path job = dir_.write("bad.json", R"({"version": 1, "scene": {"objects": [{"file": "m.obj"}]},
                                                  "render": {"width": -5}})");
  const auto r = run_command(farm("render " + shell_quote(job.string())));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("render.width"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bad.json"), std::string::npos) << r.output;
}

TEST_F(FarmCliTest, MissingModelFileExitsWith2AndNamesIt) {
  const fs::path job = dir_.write("nomodel.json",
                                 R"({"version": 1, "scene": {"objects": [{"file": "missing.dae"}]}})");
  const auto r = run_command(farm("render " + shell_quote(job.string())));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("missing.dae"), std::string::npos) << r.output;
}

// The first thing a new user meets (issue #32): the example cow job names ../shared/assets, and
// the refusal says how to let it reach there, in render and in submit alike.
TEST_F(FarmCliTest, AModelOutsideTheAssetRootIsRefusedWithTheAssetRootHint) {
  std::ofstream(dir_ / "m.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const fs::path job = dir_.write("jobs/outside.json", R"({"version": 1, "scene": {"objects": [{"file": "../m.obj"}]}})");
  for (const std::string command : {"render", "submit --scheduler 127.0.0.1:1"}) {
    const auto r = run_command(farm(command + " " + shell_quote(job.string())));
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.output;
    EXPECT_NE(r.output.find("lies outside the asset root"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("give --asset-root DIR"), std::string::npos) << r.output;
  }
  const auto ok = run_command(farm("render " + shell_quote(job.string()) + " --asset-root " +
                                   shell_quote(dir_.path().string()) + " --quiet --out " +
                                   shell_quote((dir_ / "o.exr").string()) + " --preview none"));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

TEST_F(FarmCliTest, PathEngineRendersTheCornellBoxWithFiniteColours) {
  const fs::path exr = dir_ / "p.exr";
  const auto r = run_command(farm("render " + shell_quote((kSource / "jobs/cornell.json").string()) +
                                  " --engine path --spp 4 --width 32 --height 32 --preview none --out " +
                                  shell_quote(exr.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const TileBuffer image = read_exr(exr);
  float brightest = 0.0f;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const glm::vec4 c = image.rgba(x, y);
      ASSERT_TRUE(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z)) << x << "," << y;
      brightest = std::max(brightest, c.x);
    }
  EXPECT_GT(brightest, 1.0f);  // the emissive ceiling panel (Ke 17, 12, 4) is in view
}

TEST_F(FarmCliTest, OutOfRangeOptionExitsWith2) {
  const auto r = run_command(farm("render " + shell_quote((kSource / "jobs/cornell.json").string()) +
                                  " --width 0"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--width"), std::string::npos) << r.output;
}

TEST_F(FarmCliTest, HelpExplainsTheCommandsAndExitsZero) {
  const auto r = run_command(farm("--help"));
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("render"), std::string::npos);
  EXPECT_NE(r.output.find("info"), std::string::npos);
  const auto rr = run_command(farm("render --help"));
  EXPECT_EQ(rr.exit_code, 0);
  EXPECT_NE(rr.output.find("--tile-size"), std::string::npos);
}

TEST_F(FarmCliTest, InfoPrintsAModelsTriangleCount) {
  const auto r = run_command(farm("info " + shell_quote((kSource / "jobs/assets/cornell_box.obj").string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("32 triangles"), std::string::npos) << r.output;
}

TEST_F(FarmCliTest, InfoOfAJobListsObjectsAndSettings) {
  const auto r = run_command(farm("info " + shell_quote((kSource / "jobs/torus.json").string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 object(s)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("engine raster"), std::string::npos) << r.output;
}

// The example Cornell box with its lamp's winding reversed: the lamp (1 cm under the ceiling)
// then shines into the ceiling, and `farm info` says so, naming the object and material; the
// model as shipped, or the flipped one whose job says "emission_sides": "both", draw no warning.
TEST_F(FarmCliTest, InfoWarnsAboutALampThatShinesAwayFromTheScene) {
  std::string obj = test::read_file(kSource / "jobs/assets/cornell_box.obj");
  const std::string lamp_face = "f 61 62 63 64";
  ASSERT_NE(obj.find(lamp_face), std::string::npos);
  obj.replace(obj.find(lamp_face), lamp_face.size(), "f 64 63 62 61");
  dir_.write("flipped.obj", obj);
  fs::copy_file(kSource / "jobs/assets/cornell_box.mtl", dir_ / "cornell_box.mtl");
  fs::copy_file(kSource / "jobs/assets/cornell_box.obj", dir_ / "cornell_box.obj");
  const auto job = [&](const std::string& name, const std::string& file, const std::string& material) {
    return dir_.write(name, R"({"version": 1, "scene": {"objects": [{"file": ")" + file + "\"" + material +
                                R"(}]}, "render": {"engine": "path"}})");
  };
  const std::string warning = "warning: object 'flipped' material 'light': 2 of 2 emissive triangles shine away";

  const auto flipped = run_command(farm("info " + shell_quote(job("flipped.json", "flipped.obj", "").string())));
  ASSERT_EQ(flipped.exit_code, 0) << flipped.output;
  EXPECT_NE(flipped.output.find(warning), std::string::npos) << flipped.output;
  const auto model = run_command(farm("info " + shell_quote((dir_ / "flipped.obj").string())));
  EXPECT_NE(model.output.find(warning), std::string::npos) << model.output;

  const auto both = run_command(farm("info " + shell_quote(
      job("both.json", "flipped.obj", R"(, "material": {"emission_sides": "both"})").string())));
  ASSERT_EQ(both.exit_code, 0) << both.output;
  EXPECT_EQ(both.output.find("warning"), std::string::npos) << both.output;
  const auto shipped = run_command(farm("info " + shell_quote(job("shipped.json", "cornell_box.obj", "").string())));
  ASSERT_EQ(shipped.exit_code, 0) << shipped.output;
  EXPECT_EQ(shipped.output.find("warning"), std::string::npos) << shipped.output;
}

}  // namespace
}  // namespace farm

namespace farm {
namespace {

TEST_F(FarmCliTest, ShowBvhDrawsBoxesOverThePreviewOnly) {
  const std::string job = test::shell_quote((kSource / "jobs/whitted.json").string());
  const fs::path plain = dir_ / "plain.png", boxes = dir_ / "boxes.png";
  const fs::path plain_exr = dir_ / "plain.exr", boxes_exr = dir_ / "boxes.exr";
  const std::string common = " --width 96 --height 96 --spp 1 --float";
  ASSERT_EQ(run_command(farm("render " + job + common + " --out " + test::shell_quote(plain_exr.string()) +
                             " --preview " + test::shell_quote(plain.string()))).exit_code, 0);
  const auto r = run_command(farm("render " + job + common + " --show-bvh 2 --out " +
                                  test::shell_quote(boxes_exr.string()) + " --preview " +
                                  test::shell_quote(boxes.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("BVH levels <= 2"), std::string::npos) << r.output;
  // The EXR stays clean; the preview differs (the lines).
  const TileBuffer a = read_exr(plain_exr), b = read_exr(boxes_exr);
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) ASSERT_EQ(a.rgba(x, y), b.rgba(x, y));
  std::ifstream pa(plain, std::ios::binary), pb(boxes, std::ios::binary);
  const std::string sa((std::istreambuf_iterator<char>(pa)), {}), sb((std::istreambuf_iterator<char>(pb)), {});
  EXPECT_NE(sa, sb);
}

TEST_F(FarmCliTest, WhittedBvhCostAovCountsTraversalWork) {
  const fs::path exr = dir_ / "cost.exr";
  const auto r = run_command(farm("render " + shell_quote((kSource / "jobs/whitted.json").string()) +
                                  " --width 64 --height 64 --spp 1 --preview none --out " +
                                  shell_quote(exr.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const TileBuffer image = read_exr(exr);
  ASSERT_TRUE(image.aovs().bvh_cost);
  // Every pixel of the closed box is a hit that took at least a root visit and a triangle test,
  // and far fewer than the scene's 7968 triangles.
  EXPECT_GE(image.bvh_cost(32, 32), 2.0f);
  EXPECT_LT(image.bvh_cost(32, 32), 1000.0f);
}

TEST_F(FarmCliTest, PathVarianceAovReachesTheExrAsFloatChannels) {
  // The Cornell box beside a job that asks for the variance alone.
  fs::copy_file(kSource / "jobs/assets/cornell_box.obj", dir_ / "cornell_box.obj");
  fs::copy_file(kSource / "jobs/assets/cornell_box.mtl", dir_ / "cornell_box.mtl");
  const fs::path job = dir_.write("variance.json", R"({"version": 1,
    "scene": {"objects": [{"file": "cornell_box.obj"}], "lights": [], "background": [0, 0, 0],
              "camera": {"position": [0, 0, 3.9], "target": [0, 0, 0], "fov_y": 40, "far": 20}},
    "render": {"engine": "path", "width": 40, "height": 40, "spp": 8, "max_depth": 3, "tile_size": 16},
    "output": {"aovs": ["variance"]}})");
  const fs::path exr = dir_ / "v.exr";
  const auto r = run_command(farm("render " + shell_quote(job.string()) + " --preview none --out " +
                                  shell_quote(exr.string())));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("RGBA + variance"), std::string::npos) << r.output;
  {
    Imf::InputFile in(exr.c_str());
    for (const char* name : {"variance.R", "variance.G", "variance.B"}) {
      const Imf::Channel* channel = in.header().channels().findChannel(name);
      ASSERT_NE(channel, nullptr) << name;
      EXPECT_EQ(channel->type, Imf::FLOAT) << name << ": 32-bit even in a half EXR";
    }
    EXPECT_EQ(in.header().channels().findChannel("Z"), nullptr);
  }
  const TileBuffer image = read_exr(exr);
  ASSERT_TRUE(image.aovs().variance);
  EXPECT_FALSE(image.aovs().depth || image.aovs().normal || image.aovs().albedo);
  // Lit walls are noisy at 8 spp, and nothing is negative.
  int noisy = 0;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) {
      const glm::vec3 v = image.variance(x, y);
      ASSERT_TRUE(v.x >= 0.0f && v.y >= 0.0f && v.z >= 0.0f) << x << "," << y;
      noisy += v.x > 0.0f ? 1 : 0;
    }
  }
  EXPECT_GT(noisy, 40 * 40 / 2);
}

TEST_F(FarmCliTest, BenchPathReportsThroughputAndRaysPerSample) {
  const auto r = run_command("cd " + shell_quote(kSource.string()) + " && " +
                             farm("bench path --scene cornell --threads 1 --spp 1 --width 32 --height 32 --repeats 3"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("median of 3 rounds"), std::string::npos) << r.output;
  // "farm path  1  seconds  Msamples/s  Mrays/s  rays/sample  speedup"
  const auto row = r.output.find("farm path");
  ASSERT_NE(row, std::string::npos) << r.output;
  int threads = 0;
  double seconds = 0, msamples = 0, mrays = 0, rays_per_sample = 0;
  ASSERT_EQ(std::sscanf(r.output.c_str() + row, "farm path %d %lf %lf %lf %lf", &threads, &seconds,
                        &msamples, &mrays, &rays_per_sample), 5) << r.output;
  EXPECT_EQ(threads, 1);
  EXPECT_GT(msamples, 0.0);
  // Nearly every camera ray hits the room, then traces a shadow ray and a bounce at least.
  EXPECT_GE(rays_per_sample, 2.0) << r.output;
  EXPECT_NEAR(mrays / msamples, rays_per_sample, 0.02 * rays_per_sample);
}

// The ray benchmark at every thread count asked for: a table each, with Embree called directly
// beside the farm's adapter, and the direct Embree's closest hits equal to our BVH's (the bench
// stops with an error otherwise: the anchor must trace the same scene).
TEST_F(FarmCliTest, BenchRtTimesEmbreeDirectlyAtEachThreadCountOnTheSameScene) {
  const auto r = run_command(farm("bench rt --rays 2000 --threads 1,2 --assets " + shell_quote(FARM_SHARED_ASSETS)));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::set<std::string> tables;  // "scene, N thread(s)"
  int direct = 0, ratios = 0, spreads = 0;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    for (const char* threads : {" 1 thread,", " 2 threads,"}) {
      if (line.find(" rays per set") != std::string::npos && line.find(threads) != std::string::npos) {
        tables.insert(line.substr(0, line.find(':')) + threads);
      }
    }
    direct += line.rfind("embree-direct ", 0) == 0;
    ratios += line.rfind("bvh/embree-direct ", 0) == 0;
    // Under each table, the spread of the rounds' own ratios: six "low-highx" cells, low <= high.
    if (line.rfind("bvh/embree-direct, rounds ", 0) == 0) {
      ++spreads;
      std::istringstream cells(line.substr(std::string("bvh/embree-direct, rounds ").size()));
      int columns = 0;
      for (std::string cell; cells >> cell; ++columns) {
        double low = 0.0, high = 0.0;
        char dash = 0, x = 0;
        std::istringstream parts(cell);
        ASSERT_TRUE(parts >> low >> dash >> high >> x) << line;
        EXPECT_EQ(dash, '-') << line;
        EXPECT_EQ(x, 'x') << line;
        EXPECT_GT(low, 0.0) << line;
        EXPECT_LE(low, high) << line;
      }
      EXPECT_EQ(columns, 6) << line;
    }
  }
  EXPECT_EQ(tables.size(), 8u) << r.output;  // four scenes, two thread counts
  EXPECT_EQ(direct, 8) << r.output;
  EXPECT_EQ(ratios, 8) << r.output;
  EXPECT_EQ(spreads, 8) << r.output;
  // Its first line names the machine the figures belong to: the CPU as /proc/cpuinfo calls it,
  // the hardware threads and the traversal build this CPU runs.
  std::string model = "unknown CPU";
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) != 0) continue;
    model = line.substr(line.find(':') + 2);
    while (!model.empty() && model.back() == ' ') model.pop_back();
    break;
  }
  const std::string machine = fmt::format(", {}, {} hardware threads, {} ray traversal)", model,
                                          std::thread::hardware_concurrency(), to_string(best_traversal_isa()));
  EXPECT_NE(r.output.substr(0, r.output.find('\n')).find(machine), std::string::npos) << machine << "\n" << r.output;
}

// `bench rt --model`: the models named, each one object, instead of the lab's four scenes; the
// same anchors (and the same check that Embree called directly hits what our BVH hits).
TEST_F(FarmCliTest, BenchRtTimesTheModelsItIsGivenInsteadOfTheLabsScenes) {
  const std::string assets = FARM_SHARED_ASSETS;
  const auto r = run_command(farm("bench rt --rays 2000 --repeats 1 --model " + shell_quote(assets + "/dae/teapot.dae") +
                                  " --model " + shell_quote(assets + "/obj/cube.obj")));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\nteapot.dae: 2464 triangles, 1 object(s); 2000 rays per set"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\ncube.obj: 12 triangles, 1 object(s); 2000 rays per set"), std::string::npos) << r.output;
  for (const char* lab : {"cow.dae:", "bunny.dae:", "CBbunny.dae:", "cow-grid-100:", "\nnaive "}) {
    EXPECT_EQ(r.output.find(lab), std::string::npos) << lab << "\n" << r.output;
  }
  std::istringstream lines(r.output);
  int direct = 0;
  for (std::string line; std::getline(lines, line);) direct += line.rfind("bvh/embree-direct ", 0) == 0;
  EXPECT_EQ(direct, 2) << r.output;

  const auto missing = run_command(farm("bench rt --model /nonexistent/scan.obj"));
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("/nonexistent/scan.obj"), std::string::npos) << missing.output;
}

// The dispatch benchmark claims every queued job once, as many as asked or as are queued (it
// stops with an error naming the claim otherwise). Plain, every job claimed in queue order (the bench checks it, exit 1 otherwise); in play, the
// jobs that need a tag the bench worker lacks are never claimed: 1 of 3, 4 of 40.
TEST_F(FarmCliTest, BenchDispatchClaimsEachQueuedJobOnceInQueueOrder) {
  const auto r = run_command(farm("bench dispatch --queued 3,40 --claims 25 --owners 4"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const auto& [queued, jobs, claims] : {std::tuple{3, "plain", 3}, std::tuple{40, "plain", 25},
                                             std::tuple{3, "in play", 2}, std::tuple{40, "in play", 25}}) {
    const std::string start = fmt::format("\n{:>8} {:>8} {:>8} ", queued, jobs, claims);
    const auto row = r.output.find(start);
    ASSERT_NE(row, std::string::npos) << start << "\n" << r.output;
    double fill = 0, median = 0, p99 = 0, mean = 0, per_second = 0;
    ASSERT_EQ(std::sscanf(r.output.c_str() + row + start.size(), " %lf %lf %lf %lf %lf", &fill, &median, &p99, &mean,
                          &per_second), 5) << r.output;
    EXPECT_GT(median, 0.0);
    EXPECT_GE(p99, median);
  }
}

}  // namespace
}  // namespace farm
