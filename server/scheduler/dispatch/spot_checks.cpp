#include "server/scheduler/dispatch/spot_checks.h"

#include <algorithm>

#include "server/common/tile_result_check.h"

namespace farm {

namespace {

// SplitMix64's finalizer: a bijection that spreads every input bit over the output.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

std::uint64_t hash_of(std::uint64_t key, const std::string& job_id) {
  std::uint64_t h = mix(key);
  for (unsigned char c : job_id) h = mix(h ^ c);
  return h;
}

}  // namespace

SpotCheckChooser::SpotCheckChooser(double fraction, std::uint64_t key)
    : fraction_(std::clamp(fraction, 0.0, 1.0)), key_(key) {}

bool SpotCheckChooser::chosen(const std::string& job_id, std::uint32_t index, std::uint32_t tiles) const {
  if (fraction_ <= 0.0 || tiles == 0) return false;
  const std::uint64_t job = hash_of(key_, job_id);
  if (index == mix(job) % tiles) return true;  // every job has one
  // The top 53 bits as a uniform double in [0, 1).
  const double u = static_cast<double>(mix(job ^ mix(index)) >> 11) * 0x1.0p-53;
  return u < fraction_;
}

std::optional<UnitSpan> SpotCheckChooser::span(const UnitBatch& batch, std::uint32_t tiles,
                                               const UnitGrid& grid) const {
  std::optional<std::uint32_t> first, last;
  for (std::uint32_t i = batch.first; i < batch.first + batch.count; ++i) {
    if (!chosen(batch.job_id, i, tiles)) continue;
    if (!first) first = i;
    last = i;
  }
  if (!first) return std::nullopt;
  const Rect a = grid.rect_of(*first), b = grid.rect_of(*last);
  if (a.y0 == b.y0) return UnitSpan{*first, *last - *first + 1, Rect{a.x0, a.y0, b.x1, b.y1}};
  // Chosen units in different rows of a batch of whole rows: the span takes those rows whole,
  // which keeps it one rectangle.
  const std::uint32_t from = *first - grid.column_of(*first);
  const std::uint32_t to = *last + (grid.columns() - 1 - grid.column_of(*last));
  return UnitSpan{from, to - from + 1, Rect{batch.rect.x0, a.y0, batch.rect.x1, b.y1}};
}

Judgement judge(std::vector<Opinion>& opinions, Opinion next) {
  Judgement j;
  for (std::size_t i = 0; i < opinions.size(); ++i) {
    if (!same_tile_bits(opinions[i].tile, next.tile)) continue;
    j.outcome = Judgement::Outcome::Agreed;
    j.agreed_with = i;
    for (std::size_t k = 0; k < opinions.size(); ++k) {
      if (k != i) j.wrong.push_back(k);
    }
    return j;
  }
  opinions.push_back(std::move(next));
  j.outcome = opinions.size() >= 3 ? Judgement::Outcome::NoAgreement : Judgement::Outcome::NeedAnother;
  return j;
}

}  // namespace farm
