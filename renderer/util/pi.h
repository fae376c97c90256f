#pragma once
// Pi as the engines compute with it (float), one definition for every file: unity builds put
// several files in one unit, where each file's own would collide.
#include <numbers>

namespace farm {

inline constexpr float kPi = std::numbers::pi_v<float>;

}  // namespace farm
