#pragma once
// Arbitrary output variables a render can carry beside RGBA (DESIGN.md, engine contract).
#include <optional>
#include <string_view>

namespace farm {

enum class Aov { Depth, Normal, Albedo, BvhCost };
inline constexpr Aov kAllAovs[] = {Aov::Depth, Aov::Normal, Aov::Albedo, Aov::BvhCost};

std::string_view to_string(Aov aov);               // job-file name: depth, normal, albedo, bvh_cost
std::optional<Aov> aov_from_string(std::string_view name);

struct AovSet {
  bool depth = false, normal = false, albedo = false, bvh_cost = false;

  bool has(Aov a) const {
    switch (a) {
      case Aov::Depth: return depth;
      case Aov::Normal: return normal;
      case Aov::Albedo: return albedo;
      case Aov::BvhCost: return bvh_cost;
    }
    return false;
  }
  void add(Aov a) {
    switch (a) {
      case Aov::Depth: depth = true; break;
      case Aov::Normal: normal = true; break;
      case Aov::Albedo: albedo = true; break;
      case Aov::BvhCost: bvh_cost = true; break;
    }
  }
};

}  // namespace farm
