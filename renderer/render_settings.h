#pragma once
// How to render: the job's `render` block plus the AOVs asked for in `output`.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "renderer/image/aov.h"

namespace farm {

enum class EngineKind { Raster, Whitted, Path };
// Every engine's name as job files and the command line spell it, in EngineKind's order: the one
// list that to_string, engine_from_string, the job parser's messages and `farm`'s checks share.
inline constexpr std::array<std::string_view, 3> kEngineNames = {"raster", "whitted", "path"};
enum class AccelKind { Bvh, BvhMedian, Naive, Embree };
// How the path tracer finds light: next-event estimation combined with BSDF sampling by MIS
// (the default), or BSDF sampling alone (a reference for checking MIS; point lights, which
// BSDF sampling can never hit, then contribute nothing).
enum class LightSampling { NeeMis, BsdfOnly };

std::string_view to_string(EngineKind e);
std::string_view to_string(AccelKind a);
std::optional<EngineKind> engine_from_string(std::string_view s);
std::optional<AccelKind> accel_from_string(std::string_view s);
std::string_view to_string(LightSampling l);
std::optional<LightSampling> light_sampling_from_string(std::string_view s);

struct RenderSettings {
  EngineKind engine = EngineKind::Raster;
  int width = 640;
  int height = 480;
  int spp = 1;
  int max_depth = 5;         // scattering events; -1 = unbounded (path tracer, Russian roulette)
  std::uint64_t seed = 0;
  int tile_size = 32;
  int threads = 0;           // 0 = all hardware threads
  AccelKind accel = AccelKind::Bvh;
  bool shadows = true;       // whitted: shadow rays (off: every light reaches every point)
  LightSampling light_sampling = LightSampling::NeeMis;  // path
  AovSet aovs;               // extra channels beyond RGBA
};

}  // namespace farm
