#pragma once
// The numeric limits of a job's render settings, in one place: the job file's parser (job.cpp)
// and the command line's overrides (--width, --spp, --threads, ...) check against the same
// constants, so a value one of them accepts the other accepts too.

#include <cstddef>
#include <cstdint>

#include "renderer/image/image_limits.h"

namespace farm {

// The job file's text: job files are small (the models are separate files); `farm render`,
// `farm submit` and the scheduler's SubmitJob refuse bigger ones before parsing them.
inline constexpr std::uint64_t kMaxJobFileBytes = std::uint64_t{16} << 20;
// name: it names the result files (out/<name>.exr, the scheduler's results/<job>/<name>.exr and
// their temporary siblings), and a file name has at most 255 bytes on every usual file system.
inline constexpr std::size_t kMaxNameBytes = 200;

// render.width and render.height: kMaxImageSide (image/image_limits.h).
// render.tile_size: a tile larger than the largest image renders as one that size would.
inline constexpr int kMaxTileSize = kMaxImageSide;
// render.spp: 2^20 samples per pixel is beyond any reference render; more is a typo.
inline constexpr int kMaxSpp = 1 << 20;
// validate.embree_rays (and `farm validate --rays`): each ray is traced twice, by our BVH and by
// Embree, at about ten million a second here: 10^8 is a 20 s check. `farm render` had no bound
// (issue #32: 10^12 took 4 GB in 5 s before it was stopped); a scheduler's --max-embree-rays is
// lower still.
inline constexpr std::int64_t kMaxEmbreeRays = 100'000'000;
// render.threads (0 = all hardware threads): each is a std::thread, so a count no machine has is
// refused rather than attempted.
inline constexpr int kMaxThreads = 1024;

}  // namespace farm
