#include "renderer/image/pass_merge.h"

#include <fmt/format.h>
#include <stdexcept>

namespace farm {
namespace {

// The AOVs a pixel takes from its first sample (those TileBuffer::paste copies from pass 0).
AovSet first_sample_aovs(const AovSet& aovs) {
  AovSet first = aovs;
  first.variance = false;
  return first;
}

bool carries(const AovSet& have, const AovSet& need) {
  for (Aov a : kAllAovs) {
    if (need.has(a) && !have.has(a)) return false;
  }
  return true;
}

}  // namespace

void PassAccumulator::reset(const Rect& rect, const AovSet& aovs) {
  rect_ = rect.empty() ? Rect{} : rect;
  aovs_ = aovs;
  stats_ = RenderStats{};
  const std::size_t n = static_cast<std::size_t>(rect_.width()) * static_cast<std::size_t>(rect_.height());
  samples_.assign(n, 0);
  mean_.assign(n, glm::dvec4(0.0));
  variance_.assign(aovs.variance ? n : 0, glm::dvec3(0.0));
  first_.reset(rect_, first_sample_aovs(aovs));
}

std::optional<std::pair<int, int>> PassAccumulator::first_not_at(const Rect& overlap, int count) const {
  for (int y = overlap.y0; y < overlap.y1; ++y) {
    for (int x = overlap.x0; x < overlap.x1; ++x) {
      if (samples_[index(x, y)] != count) return std::pair{x, y};
    }
  }
  return std::nullopt;
}

bool PassAccumulator::can_add(const Rect& rect, SampleRange samples) const {
  const Rect overlap = rect_.intersect(rect);
  return !samples.empty() && !overlap.empty() && !first_not_at(overlap, samples.begin);
}

void PassAccumulator::add(const TileBuffer& pass, SampleRange samples) {
  if (samples.empty() || samples.begin < 0) {
    throw std::invalid_argument(fmt::format("pass merge: samples [{}, {}) is no pass", samples.begin, samples.end));
  }
  const Rect overlap = rect_.intersect(pass.rect());
  if (overlap.empty()) {
    throw std::invalid_argument("pass merge: the pass buffer has no pixels in this image (a stopped render's?)");
  }
  if (!carries(pass.aovs(), aovs_)) {
    throw std::invalid_argument("pass merge: the pass buffer lacks AOVs the merged image carries");
  }
  // Every pixel first, so that a refused pass changes nothing.
  if (const std::optional<std::pair<int, int>> at = first_not_at(overlap, samples.begin)) {
    const auto [x, y] = *at;
    throw std::invalid_argument(fmt::format(
        "pass merge: pixel ({}, {}) holds samples [0, {}); samples [{}, {}) cannot follow them "
        "(passes fold in order, each once)",
        x, y, samples_[index(x, y)], samples.begin, samples.end));
  }

  const double nb = static_cast<double>(samples.count());
  for (int y = overlap.y0; y < overlap.y1; ++y) {
    for (int x = overlap.x0; x < overlap.x1; ++x) {
      const std::size_t i = index(x, y);
      const glm::dvec4 mb(pass.rgba(x, y));
      if (samples_[i] == 0) {
        // The pass's own floats, untouched: one pass merges to itself bit for bit.
        mean_[i] = mb;
        if (aovs_.variance) variance_[i] = glm::dvec3(pass.variance(x, y));
      } else {
        const double na = static_cast<double>(samples_[i]), n = na + nb;
        const glm::dvec4 delta = mb - mean_[i];
        mean_[i] += delta * (nb / n);
        if (aovs_.variance) {
          const glm::dvec3 d(delta);
          const glm::dvec3 m2 = variance_[i] * (na * (na - 1.0)) +
                                glm::dvec3(pass.variance(x, y)) * (nb * (nb - 1.0)) +
                                d * d * (na * nb / n);
          variance_[i] = m2 / (n * (n - 1.0));  // n >= 2: both sides hold a sample
        }
      }
      samples_[i] += samples.count();
    }
  }
  if (samples.begin == 0) first_.paste(pass);
  stats_ += pass.stats();
}

void PassAccumulator::resolve(TileBuffer& out) const {
  out.reset_for_overwrite(rect_, aovs_);
  out.paste(first_);  // the first-sample AOVs, and an RGBA overwritten below
  for (int y = rect_.y0; y < rect_.y1; ++y) {
    for (int x = rect_.x0; x < rect_.x1; ++x) {
      const std::size_t i = index(x, y);
      out.rgba(x, y) = glm::vec4(mean_[i]);
      if (aovs_.variance) out.variance(x, y) = glm::vec3(variance_[i]);
    }
  }
  out.stats() = stats_;
}

TileBuffer PassAccumulator::resolve() const {
  TileBuffer out;
  resolve(out);
  return out;
}

}  // namespace farm
