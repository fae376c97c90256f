#include "renderer/geometry/traversal_isa.h"

#include <stdexcept>

namespace farm {

bool cpu_has_avx2() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has;
}

namespace detail {
std::atomic<TraversalIsa> traversal_isa_in_use{cpu_has_avx2() ? TraversalIsa::Avx2 : TraversalIsa::Sse};
}  // namespace detail

void force_traversal_isa(std::optional<TraversalIsa> isa) {
  if (isa == TraversalIsa::Avx2 && !cpu_has_avx2()) {
    throw std::invalid_argument("this CPU has no AVX2: the BVH traversal runs on SSE");
  }
  detail::traversal_isa_in_use.store(isa.value_or(cpu_has_avx2() ? TraversalIsa::Avx2 : TraversalIsa::Sse),
                                     std::memory_order_relaxed);
}

std::string_view to_string(TraversalIsa isa) { return isa == TraversalIsa::Avx2 ? "avx2" : "sse"; }

}  // namespace farm
