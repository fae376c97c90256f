#pragma once
// Which build of the BVH traversal a query runs (bvh_traversal.h): AVX2 where the CPU has it,
// else SSE, the x86-64 baseline every CPU has. Both give the same hits and visit the same
// nodes, so the choice changes speed only; tests and `farm bench rt --isa` force one to compare.
#include <atomic>
#include <optional>
#include <string_view>

namespace farm {

enum class TraversalIsa { Sse, Avx2 };

namespace detail {
// Set from the CPU when the program starts (zero, Sse, until then: safe anywhere).
extern std::atomic<TraversalIsa> traversal_isa_in_use;
}  // namespace detail

// Read per query, so a relaxed load.
inline TraversalIsa traversal_isa() { return detail::traversal_isa_in_use.load(std::memory_order_relaxed); }

bool cpu_has_avx2();

// Runs every later query on `isa` (nullopt: the CPU's best). Throws std::invalid_argument for
// AVX2 on a CPU without it.
void force_traversal_isa(std::optional<TraversalIsa> isa);

std::string_view to_string(TraversalIsa isa);

}  // namespace farm
