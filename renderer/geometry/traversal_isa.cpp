#include "renderer/geometry/traversal_isa.h"

#include <fmt/format.h>

#include <stdexcept>

namespace farm {

bool cpu_runs(TraversalIsa isa) {
  switch (isa) {
    case TraversalIsa::Sse:
      return true;
    case TraversalIsa::Avx2:
      return cpu_has_avx2();
    case TraversalIsa::Avx512:
      return cpu_has_avx512();
  }
  return false;
}

TraversalIsa best_traversal_isa() {
  return cpu_has_avx512() ? TraversalIsa::Avx512 : cpu_has_avx2() ? TraversalIsa::Avx2 : TraversalIsa::Sse;
}

namespace detail {
std::atomic<TraversalIsa> traversal_isa_in_use{best_traversal_isa()};
}  // namespace detail

void force_traversal_isa(std::optional<TraversalIsa> isa) {
  if (isa && !cpu_runs(*isa)) {
    throw std::invalid_argument(
        fmt::format("this CPU has no {}: the BVH traversal runs on {}", to_string(*isa), to_string(best_traversal_isa())));
  }
  detail::traversal_isa_in_use.store(isa.value_or(best_traversal_isa()), std::memory_order_relaxed);
}

std::string_view to_string(TraversalIsa isa) {
  switch (isa) {
    case TraversalIsa::Sse:
      return "sse";
    case TraversalIsa::Avx2:
      return "avx2";
    case TraversalIsa::Avx512:
      return "avx512";
  }
  return "?";
}

}  // namespace farm
