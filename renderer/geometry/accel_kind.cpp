#include "renderer/geometry/accel_kind.h"

namespace farm {

std::string_view to_string(AccelKind a) {
  switch (a) {
    case AccelKind::Bvh: return "bvh";
    case AccelKind::BvhMedian: return "bvh-median";
    case AccelKind::Naive: return "naive";
    case AccelKind::Embree: return "embree";
  }
  return "?";
}

std::optional<AccelKind> accel_from_string(std::string_view s) {
  for (AccelKind a : {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive, AccelKind::Embree}) {
    if (to_string(a) == s) return a;
  }
  return std::nullopt;
}

}  // namespace farm
