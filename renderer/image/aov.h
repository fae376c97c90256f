#pragma once
// Arbitrary output variables a render can carry beside RGBA (docs/architecture.md, "The engine contract").
#include <optional>
#include <string_view>

namespace farm {

// Variance: per colour channel, the variance of the pixel's mean estimate (the path tracer's
// Monte Carlo noise); engines whose pixel is no Monte Carlo estimate write zeros.
enum class Aov { Depth, Normal, Albedo, BvhCost, Variance };
inline constexpr Aov kAllAovs[] = {Aov::Depth, Aov::Normal, Aov::Albedo, Aov::BvhCost, Aov::Variance};

// Job-file name: depth, normal, albedo, bvh_cost, variance.
std::string_view to_string(Aov aov);
std::optional<Aov> aov_from_string(std::string_view name);

struct AovSet {
  bool depth = false, normal = false, albedo = false, bvh_cost = false, variance = false;
  bool operator==(const AovSet&) const = default;

  bool has(Aov a) const {
    switch (a) {
      case Aov::Depth: return depth;
      case Aov::Normal: return normal;
      case Aov::Albedo: return albedo;
      case Aov::BvhCost: return bvh_cost;
      case Aov::Variance: return variance;
    }
    return false;
  }
  void add(Aov a) {
    switch (a) {
      case Aov::Depth: depth = true; break;
      case Aov::Normal: normal = true; break;
      case Aov::Albedo: albedo = true; break;
      case Aov::BvhCost: bvh_cost = true; break;
      case Aov::Variance: variance = true; break;
    }
  }
};

}  // namespace farm
