#pragma once
// How to render: the job's `render` block plus the AOVs asked for in `output`.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "renderer/geometry/accel_kind.h"
#include "renderer/image/aov.h"
#include "renderer/image/sample_range.h"

namespace farm {

enum class EngineKind { Raster, Whitted, Path };
// Every engine's name as job files and the command line spell it, in EngineKind's order: the one
// list that to_string, engine_from_string, the job parser's messages and `farm`'s checks share.
inline constexpr std::array<std::string_view, 3> kEngineNames = {"raster", "whitted", "path"};
// How the path tracer finds light: next-event estimation combined with BSDF sampling by MIS
// (the default), or BSDF sampling alone (a reference for checking MIS; point lights, which
// BSDF sampling can never hit, then contribute nothing).
enum class LightSampling { NeeMis, BsdfOnly };

std::string_view to_string(EngineKind e);
std::optional<EngineKind> engine_from_string(std::string_view s);
std::string_view to_string(LightSampling l);
std::optional<LightSampling> light_sampling_from_string(std::string_view s);

struct RenderSettings {
  EngineKind engine = EngineKind::Raster;
  int width = 640;
  int height = 480;
  int spp = 1;
  // Sample passes (path engine): each pixel's spp samples split into passes of pass_spp samples,
  // pass p taking the global samples [p * pass_spp, min(spp, (p + 1) * pass_spp)), so that a farm
  // can render (frame, tile, pass) units anywhere and merge them (PassAccumulator). 0 = one pass
  // of all spp samples. Raster and whitted ignore it: their extra samples only antialias, and
  // they render all of them in their one pass, pass 0.
  int pass_spp = 0;
  // The pass render_tile renders, 0 <= pass < pass_count(); -1 = all spp samples at once (what a
  // render without passes does; render_frame then renders every pass and merges them).
  int pass = -1;
  int max_depth = 5;         // scattering events; -1 = unbounded (path tracer, Russian roulette)
  std::uint64_t seed = 0;
  int frame = 0;             // keys the random numbers with the seed (trace/sampler.h)
  int tile_size = 32;
  int threads = 0;           // 0 = all hardware threads
  AccelKind accel = AccelKind::Bvh;
  bool shadows = true;       // whitted: shadow rays (off: every light reaches every point)
  LightSampling light_sampling = LightSampling::NeeMis;  // path
  AovSet aovs;               // extra channels beyond RGBA
};

// Passes a frame of `settings` is split into: ceil(spp / pass_spp) for the path engine, 1 when
// pass_spp is 0 or at least spp, and always 1 for raster and whitted (see pass_spp). Throws
// InputError for a negative pass_spp.
int pass_count(const RenderSettings& settings);

// The global sample indices of pass `pass` (0 <= pass < pass_count(settings)): the whole
// [0, spp) for a frame of one pass. Throws InputError for a pass out of range. spp below 1
// counts as 1, as the engines render it.
SampleRange pass_samples(const RenderSettings& settings, int pass);

// What one render_tile call with these settings renders: pass_samples(settings, settings.pass),
// or all of [0, spp) for pass -1. Throws InputError for a pass out of range.
SampleRange samples_to_render(const RenderSettings& settings);

}  // namespace farm
