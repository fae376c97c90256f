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
                                               const RenderSettings& settings) const {
  std::optional<std::uint32_t> first, last;
  for (std::uint32_t i = batch.first; i < batch.first + batch.count; ++i) {
    if (!chosen(batch.job_id, i, tiles)) continue;
    if (!first) first = i;
    last = i;
  }
  if (!first) return std::nullopt;
  // The grid of split_into_tiles: row by row, tile_size squares clipped to the image.
  const int size = std::max(1, settings.tile_size);
  const auto columns = static_cast<std::uint32_t>((settings.width + size - 1) / size);
  const auto rows = static_cast<std::uint32_t>((settings.height + size - 1) / size);
  const auto rect_of = [&](std::uint32_t i) {
    i %= columns * rows;  // a job of several frames numbers its tiles on, frame after frame
    const int x = static_cast<int>(i % columns) * size, y = static_cast<int>(i / columns) * size;
    return Rect{x, y, std::min(x + size, settings.width), std::min(y + size, settings.height)};
  };
  const Rect a = rect_of(*first), b = rect_of(*last);
  return UnitSpan{*first, *last - *first + 1, Rect{a.x0, a.y0, b.x1, b.y1}};
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
