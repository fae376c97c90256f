#pragma once
// The work one SubmitJob may start, in one place: a job the scheduler accepts becomes a row per
// tile in the store, its text travels with every RenderTile call, its samples keep the workers
// busy and its validation rays run in the scheduler at merge. Each limit has a default that the
// biggest honest lab scene passes easily; `farm scheduler` sets them with flags (README.md,
// "farm scheduler"). The job file's own limits (image side, spp, name length) are in
// renderer/job/job_limits.h and hold everywhere; these are the farm's, on top of them.
#include <cstdint>

#include "proto/farm.pb.h"
#include "renderer/job/job.h"
#include "renderer/job/job_limits.h"

namespace farm {

struct SubmitLimits {
  // JobSpec.job_json, checked before parsing: what `farm submit` and `farm render` read at most.
  std::uint64_t max_job_bytes = kMaxJobFileBytes;  // 16 MiB
  // Units: frames x sample passes x the tiles of a frame's grid, ceil(width / tile_size) x
  // ceil(height / tile_size). 65,536 is one 8192x8192 frame in one pass at the default tile_size
  // 32, or 16384x16384 at tile_size 64.
  std::int64_t max_tiles_per_job = 65536;
  // width x height x spp x path length (job_work below): 1e13. 4096x4096 at 4096 spp with
  // max_depth 16 is 1.2e12 and passes; 16384x16384 at 2^20 spp is refused whatever the depth.
  double max_work = 1e13;
  // validate.embree_rays: each is traced twice in the scheduler while it merges the frame.
  std::int64_t max_embree_rays = 10'000'000;
  // AssetRef.size of one file, and of all the files of one job together.
  std::uint64_t max_asset_bytes = std::uint64_t{2} << 30;      // 2 GiB
  std::uint64_t max_job_asset_bytes = std::uint64_t{4} << 30;  // 4 GiB
  // Every blob the asset store holds, together (asset_quota.h); 0 for no limit.
  std::uint64_t max_asset_store_bytes = std::uint64_t{64} << 30;  // 64 GiB
  // Loading a job's models and building its scene at submit, in a child process
  // (scene_check.h): its address space and its wall-clock time. The lab's cow loads in 0.1 s in
  // 130 MiB; a 10M-triangle model in about a minute and a few GiB.
  std::uint64_t max_scene_memory = std::uint64_t{8} << 30;  // 8 GiB
  double max_scene_seconds = 120;
  int max_scene_checks = 0;  // child processes at once; 0: half the hardware threads, at least 1
};

// The rays a sample may trace, as counted against max_work: 1 for raster; for the ray engines
// max_depth + 1 (the camera ray and one per scattering event), an unbounded path (max_depth -1,
// ended by Russian roulette) counted as max_depth 16.
std::int64_t path_length(const RenderSettings& render);
// width x height x spp x path_length, as a double: it overflows no integer.
double job_work(const RenderSettings& render);
// ceil(width / tile_size) x ceil(height / tile_size), without splitting anything.
std::int64_t job_tiles(const RenderSettings& render);

// Before the job's text is parsed: its size, and the sizes its AssetRefs declare (the store
// checks them against the files). ServiceError RESOURCE_EXHAUSTED naming the limit and the value.
void check_spec_limits(const v1::JobSpec& spec, const SubmitLimits& limits);
// After parsing `spec` into `job`, before any model is loaded or a tile is stored: tiles, work
// and validation rays. ServiceError RESOURCE_EXHAUSTED naming the JSON path, the value and the limit.
void check_job_limits(const Job& job, const v1::JobSpec& spec, const SubmitLimits& limits);

}  // namespace farm
