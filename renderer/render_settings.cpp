#include "renderer/render_settings.h"

namespace farm {

std::string_view to_string(EngineKind e) {
  switch (e) {
    case EngineKind::Raster: return "raster";
    case EngineKind::Whitted: return "whitted";
    case EngineKind::Path: return "path";
  }
  return "?";
}

std::string_view to_string(AccelKind a) {
  switch (a) {
    case AccelKind::Bvh: return "bvh";
    case AccelKind::BvhMedian: return "bvh-median";
    case AccelKind::Naive: return "naive";
    case AccelKind::Embree: return "embree";
  }
  return "?";
}

std::optional<EngineKind> engine_from_string(std::string_view s) {
  for (EngineKind e : {EngineKind::Raster, EngineKind::Whitted, EngineKind::Path}) {
    if (to_string(e) == s) return e;
  }
  return std::nullopt;
}

std::optional<AccelKind> accel_from_string(std::string_view s) {
  for (AccelKind a : {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive, AccelKind::Embree}) {
    if (to_string(a) == s) return a;
  }
  return std::nullopt;
}

std::string_view to_string(LightSampling l) {
  return l == LightSampling::NeeMis ? "nee-mis" : "bsdf";
}

std::optional<LightSampling> light_sampling_from_string(std::string_view s) {
  for (LightSampling l : {LightSampling::NeeMis, LightSampling::BsdfOnly}) {
    if (to_string(l) == s) return l;
  }
  return std::nullopt;
}

}  // namespace farm
