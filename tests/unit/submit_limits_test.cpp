// The scheduler's limits on the work one SubmitJob may start (server/scheduler/options/submit_limits.h):
// each refuses its bomb with RESOURCE_EXHAUSTED naming the limit's flag, the value and the limit,
// and the biggest honest job passes them all.
#include "server/scheduler/options/submit_limits.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "server/common/service_error.h"

namespace farm {
namespace {

Job job_of(EngineKind engine, int width, int height, int spp, int max_depth, int tile_size) {
  Job job;
  job.name = "big";
  job.render.engine = engine;
  job.render.width = width;
  job.render.height = height;
  job.render.spp = spp;
  job.render.max_depth = max_depth;
  job.render.tile_size = tile_size;
  return job;
}

v1::JobSpec spec_of(std::string json = "{}") {
  v1::JobSpec spec;
  spec.set_job_json(std::move(json));
  spec.set_file_name("big.json");
  return spec;
}

void add_asset(v1::JobSpec& spec, const std::string& path, std::uint64_t size) {
  v1::AssetRef& ref = *spec.add_assets();
  ref.set_path(path);
  ref.set_sha256(std::string(64, 'a'));
  ref.set_size(size);
}

// The refusal `check` throws: its code and message, or a failure when it passes.
ServiceError refusal(const std::function<void()>& check) {
  try {
    check();
  } catch (const ServiceError& e) {
    return e;
  }
  ADD_FAILURE() << "expected a refusal";
  return ServiceError(grpc::StatusCode::OK, "");
}

void expect_refused(const std::function<void()>& check, const std::vector<std::string>& needles) {
  const ServiceError e = refusal(check);
  EXPECT_EQ(e.code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << e.what();
  for (const std::string& needle : needles) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << "no '" << needle << "' in: " << e.what();
  }
}

TEST(SubmitLimits, TheBiggestHonestJobPassesEveryDefault) {
  // 4096x4096, 4096 spp, max_depth 16 path tracing with a million validation rays, 3 GiB of
  // models: 16,384 tiles and 1.2e12 samples x rays.
  Job job = job_of(EngineKind::Path, 4096, 4096, 4096, 16, 32);
  job.embree_rays = 1'000'000;
  v1::JobSpec spec = spec_of(std::string(1 << 20, ' '));
  add_asset(spec, "a.obj", std::uint64_t{3} << 29);
  add_asset(spec, "b.obj", std::uint64_t{3} << 29);
  const SubmitLimits limits;
  EXPECT_NO_THROW(check_spec_limits(spec, limits));
  EXPECT_NO_THROW(check_job_limits(job, spec, limits));
  EXPECT_EQ(job_tiles(job.render), 16384);
  EXPECT_DOUBLE_EQ(job_work(job.render), 4096.0 * 4096 * 4096 * 17);
  // An 8192x8192 frame at the default tile_size is exactly the tile limit; unbounded depth passes.
  EXPECT_NO_THROW(check_job_limits(job_of(EngineKind::Path, 8192, 8192, 256, -1, 32), spec, limits));
  EXPECT_NO_THROW(check_job_limits(job_of(EngineKind::Raster, 16384, 16384, 64, 5, 64), spec, limits));
}

TEST(SubmitLimits, TooManyTilesIsRefusedNamingTheCountTheLimitAndATileSizeThatFits) {
  const v1::JobSpec spec = spec_of();
  expect_refused([&] { check_job_limits(job_of(EngineKind::Raster, 16384, 16384, 1, 5, 1), spec, {}); },
                 {"big.json", "render.tile_size", "268435456 units", "at most 65536",
                  "--max-tiles-per-job", "at least 64"});
  expect_refused([&] { check_job_limits(job_of(EngineKind::Raster, 4096, 4096, 1, 5, 1), spec, {}); },
                 {"16777216 units", "at least 16"});
  expect_refused([&] { check_job_limits(job_of(EngineKind::Raster, 8193, 8192, 1, 5, 32), spec, {}); },
                 {"65792 units", "at least 33"});
}

TEST(SubmitLimits, WorkAboveTheBudgetIsRefusedNamingSamplesDepthAndTheLimit) {
  const v1::JobSpec spec = spec_of();
  // 16384x16384 at 2^20 spp: 2.8e14 camera samples before any bounce.
  expect_refused(
      [&] { check_job_limits(job_of(EngineKind::Raster, 16384, 16384, 1 << 20, 5, 128), spec, {}); },
      {"render", "16384x16384", "1048576 spp", "2.81e+14", "at most 1e+13", "--max-work"});
  // Depth counts for the ray engines: 4096x4096 at 16384 spp is 2.7e11 samples, 1.8e13 rays at
  // max_depth 63.
  EXPECT_NO_THROW(check_job_limits(job_of(EngineKind::Raster, 4096, 4096, 16384, 63, 32), spec, {}));
  expect_refused(
      [&] { check_job_limits(job_of(EngineKind::Whitted, 4096, 4096, 16384, 63, 32), spec, {}); },
      {"path length 64", "1.76e+13", "--max-work"});
  // A depth no path reaches still counts as written: the engines would try it.
  expect_refused(
      [&] { check_job_limits(job_of(EngineKind::Path, 1024, 1024, 1024, 1'000'000, 32), spec, {}); },
      {"max_depth 1000000"});
}

TEST(SubmitLimits, EmbreeRaysAboveTheLimitAreRefusedNamingTheJsonPath) {
  Job job = job_of(EngineKind::Raster, 64, 64, 1, 5, 32);
  job.embree_rays = 1'000'000'000'000;
  expect_refused([&] { check_job_limits(job, spec_of(), {}); },
                 {"validate.embree_rays", "1000000000000 rays", "at most 10000000", "--max-embree-rays"});
  job.embree_rays = 10'000'000;
  EXPECT_NO_THROW(check_job_limits(job, spec_of(), {}));
}

TEST(SubmitLimits, JobTextAboveTheLimitIsRefusedBeforeItIsParsed) {
  // Not JSON at all: the size is checked first.
  expect_refused([] { check_spec_limits(spec_of(std::string((16 << 20) + 1, 'x')), {}); },
                 {"big.json", "16777217 bytes", "at most 16777216", "--max-job-bytes"});
  EXPECT_NO_THROW(check_spec_limits(spec_of(std::string(16 << 20, 'x')), {}));
}

TEST(SubmitLimits, AssetBytesAreLimitedPerAssetAndPerJob) {
  v1::JobSpec one = spec_of();
  add_asset(one, "huge.obj", (std::uint64_t{2} << 30) + 1);
  expect_refused([&] { check_spec_limits(one, {}); },
                 {"'huge.obj'", "2147483649 bytes", "at most 2147483648", "--max-asset-bytes"});
  v1::JobSpec three = spec_of();
  for (const char* path : {"a.obj", "b.obj", "c.obj"}) add_asset(three, path, std::uint64_t{3} << 29);
  expect_refused([&] { check_spec_limits(three, {}); },
                 {"3 assets", "at most 4294967296", "--max-job-asset-bytes"});
}

TEST(SubmitLimits, EachLimitIsTheOperatorsToSet) {
  SubmitLimits tight;
  tight.max_job_bytes = 10;
  tight.max_tiles_per_job = 4;
  tight.max_work = 1e6;
  tight.max_embree_rays = 0;
  Job job = job_of(EngineKind::Raster, 64, 64, 1, 5, 32);  // 4 tiles, 4096 samples
  EXPECT_NO_THROW(check_job_limits(job, spec_of(), tight));
  expect_refused([&] { check_spec_limits(spec_of(std::string(11, ' ')), tight); }, {"at most 10"});
  job.render.tile_size = 16;
  expect_refused([&] { check_job_limits(job, spec_of(), tight); }, {"16 units", "at most 4 "});
  job.render.tile_size = 32;
  job.render.spp = 1000;
  expect_refused([&] { check_job_limits(job, spec_of(), tight); }, {"--max-work"});
  job.render.spp = 1;
  job.embree_rays = 1;
  expect_refused([&] { check_job_limits(job, spec_of(), tight); }, {"at most 0 "});
}

}  // namespace
}  // namespace farm
