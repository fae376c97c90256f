#pragma once
// Which acceleration structure answers a render's rays: our BVH (SAH, the default), our BVH split
// at the median (a reference for the SAH), no structure at all (every triangle tested: the
// reference for both), or Embree. Spelled as job files and the command line spell it.
#include <optional>
#include <string_view>

namespace farm {

enum class AccelKind { Bvh, BvhMedian, Naive, Embree };

std::string_view to_string(AccelKind a);
std::optional<AccelKind> accel_from_string(std::string_view s);

}  // namespace farm
