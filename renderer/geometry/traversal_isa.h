#pragma once
// Which build of the BVH traversal a query runs (bvh_traversal.h): AVX-512 (its VL subset, on
// 256-bit registers) where the CPU has it, else AVX2, else SSE, the x86-64 baseline every CPU
// has. All give the same hits and visit the same nodes, so the choice changes speed only; tests
// and `farm bench rt` force one to compare.
#include <atomic>
#include <optional>
#include <string_view>

#include "renderer/util/cpu_features.h"  // cpu_has_avx2, cpu_has_avx512 (AVX-512: its 8-wide code on 32 registers)

namespace farm {

// In order of preference, worst first.
enum class TraversalIsa { Sse, Avx2, Avx512 };

namespace detail {
// Set from the CPU when the program starts (zero, Sse, until then: safe anywhere).
extern std::atomic<TraversalIsa> traversal_isa_in_use;
}  // namespace detail

// Read per query, so a relaxed load.
inline TraversalIsa traversal_isa() { return detail::traversal_isa_in_use.load(std::memory_order_relaxed); }

// Whether this CPU runs `isa`'s build.
bool cpu_runs(TraversalIsa isa);
// The best build this CPU runs.
TraversalIsa best_traversal_isa();

// Runs every later query on `isa` (nullopt: the CPU's best). Throws std::invalid_argument for a
// build this CPU cannot run.
void force_traversal_isa(std::optional<TraversalIsa> isa);

// force_traversal_isa(isa) for a scope: the CPU's best again when it ends, however it ends (an
// exception, or a test's failed assertion returning early, would otherwise leave later queries,
// and later tests, on the forced build).
class ForcedTraversalIsa {
 public:
  explicit ForcedTraversalIsa(std::optional<TraversalIsa> isa) { force_traversal_isa(isa); }
  ~ForcedTraversalIsa() { force_traversal_isa(std::nullopt); }
  ForcedTraversalIsa(const ForcedTraversalIsa&) = delete;
  ForcedTraversalIsa& operator=(const ForcedTraversalIsa&) = delete;
};

std::string_view to_string(TraversalIsa isa);

}  // namespace farm
