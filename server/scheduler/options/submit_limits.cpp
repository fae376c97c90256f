#include "server/scheduler/options/submit_limits.h"

#include <fmt/format.h>

#include <algorithm>

#include "server/common/service_error.h"

namespace farm {

namespace {

// The job as its user knows it, to start messages with (as the job file's own errors do).
std::string file_of(const v1::JobSpec& spec) {
  return spec.file_name().empty() ? "the job" : spec.file_name().substr(0, 200);
}

constexpr int kUnboundedDepthCountedAs = 16;

[[noreturn]] void refuse(const std::string& message) {
  throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED, message);
}

std::int64_t tiles_at(int width, int height, int tile_size) {
  const auto across = (std::int64_t{width} + tile_size - 1) / tile_size;
  const auto down = (std::int64_t{height} + tile_size - 1) / tile_size;
  return across * down;
}

// The smallest tile_size that keeps the image within `max_tiles`, for the refusal's advice; 0
// when none does.
int smallest_tile_size(int width, int height, std::int64_t max_tiles) {
  for (int size = 1; size <= kMaxTileSize; ++size) {
    if (tiles_at(width, height, size) <= max_tiles) return size;
  }
  return 0;
}

}  // namespace

std::int64_t path_length(const RenderSettings& render) {
  if (render.engine == EngineKind::Raster) return 1;
  const int depth = render.max_depth < 0 ? kUnboundedDepthCountedAs : render.max_depth;
  return std::int64_t{depth} + 1;
}

double job_work(const RenderSettings& render) {
  return static_cast<double>(render.width) * render.height * render.spp *
         static_cast<double>(path_length(render));
}

std::int64_t job_tiles(const RenderSettings& render) {
  return tiles_at(render.width, render.height, std::max(render.tile_size, 1));
}

void check_spec_limits(const v1::JobSpec& spec, const SubmitLimits& limits) {
  const std::string file = file_of(spec);
  if (spec.job_json().size() > limits.max_job_bytes) {
    refuse(fmt::format("{}: the job text is {} bytes; the scheduler takes at most {} "
                       "(--max-job-bytes); models and other data go in asset files",
                       file, spec.job_json().size(), limits.max_job_bytes));
  }
  std::uint64_t total = 0;
  for (const v1::AssetRef& ref : spec.assets()) {
    if (ref.size() > limits.max_asset_bytes) {
      refuse(fmt::format("{}: asset '{}' is {} bytes; the scheduler takes at most {} an asset "
                         "(--max-asset-bytes)",
                         file, ref.path().substr(0, 200), ref.size(), limits.max_asset_bytes));
    }
    total += ref.size();  // each at most max_asset_bytes: no overflow short of 2^33 assets
    if (total > limits.max_job_asset_bytes) {
      refuse(fmt::format("{}: the job's {} assets are more than {} bytes together; the scheduler "
                         "takes at most {} a job (--max-job-asset-bytes)",
                         file, spec.assets_size(), total, limits.max_job_asset_bytes));
    }
  }
}

void check_job_limits(const Job& job, const v1::JobSpec& spec, const SubmitLimits& limits) {
  const std::string file = file_of(spec);
  const RenderSettings& r = job.render;
  // Every frame is as many tiles and as much work again; every sample pass as many tiles again.
  const auto frames = static_cast<std::int64_t>(job_frames(job).size());
  const auto passes = static_cast<std::int64_t>(pass_count(r));
  const std::string of_frames = frames > 1 ? fmt::format(" x {} frames", frames) : "";
  const std::string of_passes = passes > 1 ? fmt::format(" x {} sample passes", passes) : "";
  if (const std::int64_t tiles = job_tiles(r) * frames * passes; tiles > limits.max_tiles_per_job) {
    const int fits = smallest_tile_size(r.width, r.height, limits.max_tiles_per_job / (frames * passes));
    refuse(fmt::format("{}: render.tile_size: {}x{} at tile_size {}{}{} is {} units; the scheduler "
                       "takes at most {} a job (--max-tiles-per-job){}",
                       file, r.width, r.height, r.tile_size, of_frames, of_passes, tiles, limits.max_tiles_per_job,
                       fits > 0 ? fmt::format(": use a tile_size of at least {}", fits)
                       : passes > 1 ? ": use a larger render.pass_spp"
                       : frames > 1 ? ": render fewer frames a job" : ""));
  }
  if (const double work = job_work(r) * static_cast<double>(frames); work > limits.max_work) {
    refuse(fmt::format("{}: render: {}x{} pixels x {} spp x path length {} (max_depth {}){} is {:.3g} "
                       "samples x rays; the scheduler takes at most {:.3g} a job (--max-work)",
                       file, r.width, r.height, r.spp, path_length(r), r.max_depth, of_frames, work,
                       limits.max_work));
  }
  if (job.embree_rays > limits.max_embree_rays) {
    refuse(fmt::format("{}: validate.embree_rays: {} rays; the scheduler checks at most {} a job "
                       "(--max-embree-rays)",
                       file, job.embree_rays, limits.max_embree_rays));
  }
}

}  // namespace farm
