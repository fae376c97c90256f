#include "renderer/image/aov.h"

namespace farm {

std::string_view to_string(Aov aov) {
  switch (aov) {
    case Aov::Depth: return "depth";
    case Aov::Normal: return "normal";
    case Aov::Albedo: return "albedo";
    case Aov::BvhCost: return "bvh_cost";
    case Aov::Variance: return "variance";
  }
  return "?";
}

std::optional<Aov> aov_from_string(std::string_view name) {
  for (Aov a : kAllAovs) {
    if (to_string(a) == name) return a;
  }
  return std::nullopt;
}

}  // namespace farm
