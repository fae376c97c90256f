#include "renderer/util/cpu_features.h"

namespace farm {

bool cpu_has_avx2() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has;
}

bool cpu_has_avx512() {
  // libgcc's check includes the operating system's support for the registers' state (XCR0).
  static const bool has = [] {
    __builtin_cpu_init();
    return cpu_has_avx2() && __builtin_cpu_supports("avx512f") != 0 && __builtin_cpu_supports("avx512vl") != 0;
  }();
  return has;
}

}  // namespace farm
