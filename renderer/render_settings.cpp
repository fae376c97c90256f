#include "renderer/render_settings.h"

namespace farm {

std::string_view to_string(EngineKind e) {
  const auto i = static_cast<std::size_t>(e);
  return i < kEngineNames.size() ? kEngineNames[i] : "?";
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
  for (std::size_t i = 0; i < kEngineNames.size(); ++i) {
    if (kEngineNames[i] == s) return static_cast<EngineKind>(i);
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
