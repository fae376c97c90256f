#pragma once
// Merging a frame's sample passes (docs/architecture.md, "Glossary": a unit is one tile of one frame in one pass).
// Each pass's buffer is a complete image of its own samples: the mean of each pixel's samples in
// RGB and in A (coverage), the variance AOV of that mean, and its first sample's depth, normal,
// albedo and bvh_cost. Folding the passes in sample order gives the image of all of them at
// once; the progressive preview after pass k is the same fold stopped after pass k.
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "renderer/image/aov.h"
#include "renderer/image/sample_range.h"
#include "renderer/image/tile_buffer.h"

namespace farm {

// Folds pass buffers into one rectangle (a tile, or the whole frame that tiles are folded into
// one at a time), pixel by pixel, and yields at any point the TileBuffer of the samples folded
// so far. Each pixel keeps its own count, so passes of different tile splits mix freely; what
// is fixed is the order at each pixel, the order of its samples (pass 0, 1, 2, ...), and since
// every fold is the same arithmetic on the same floats, the result is bit-identical however the
// passes were rendered: which worker, how many threads, which tile split, how many retries.
//
// Per pixel, for a fold of a pass of n_b samples with mean m_b and mean variance v_b into n_a
// samples with mean m_a and mean variance v_a (Chan, Golub and LeVeque's pairwise update of the
// second moment M2 = sum (x - mean)^2, where a mean's variance is M2 / (n (n - 1))):
//   n = n_a + n_b,  delta = m_b - m_a,  m = m_a + delta n_b / n            (RGB and A alike)
//   M2 = v_a n_a (n_a - 1) + v_b n_b (n_b - 1) + delta^2 n_a n_b / n,  v = M2 / (n (n - 1))
// so a pass buffer needs nothing beyond today's channels plus its sample count (the range
// passed to add): its mean is the RGBA, and its M2 is its variance AOV times n_b (n_b - 1).
// The state is kept in double; a pixel's first fold stores the pass's floats as they are, so
// one pass comes back bit for bit (the merge of a frame without passes is the identity).
//
// Depth, normal, albedo and bvh_cost are those of the pixel's first sample, as in a render
// without passes: they come from the pass whose range begins at sample 0 and are never
// averaged (an average of depths or normals across an edge is a surface nobody hit).
//
// Memory: 36 bytes a pixel, 24 more with the variance AOV, beside the first-sample AOVs.
class PassAccumulator {
 public:
  PassAccumulator() = default;
  PassAccumulator(const Rect& rect, const AovSet& aovs) { reset(rect, aovs); }

  // Empties the accumulator and sizes it to `rect` with the AOVs the merged image will carry.
  void reset(const Rect& rect, const AovSet& aovs);

  const Rect& rect() const { return rect_; }
  const AovSet& aovs() const { return aovs_; }

  // Folds in `pass`, the buffer of the pixels' samples `samples` (a pass's global sample
  // indices, see pass_samples), over the overlap of its rect with rect(); its stats are added in
  // full. Each pixel of the overlap must hold exactly the samples before samples.begin (its
  // passes so far, in order) and `pass` must carry every AOV of aovs(); otherwise, or for an
  // empty range or no overlap (a stopped render's buffer has no pixels), throws
  // std::invalid_argument and changes nothing. A pass folded twice (a retried unit) is refused
  // the same way: the caller keeps one of the copies, which are the same bits anyway.
  // Not safe to call concurrently on one accumulator.
  void add(const TileBuffer& pass, SampleRange samples);
  // Whether a pass of `samples` over `rect` can be folded now: every pixel of its overlap with
  // rect() holds exactly the samples before samples.begin (a part that came before the passes
  // under it waits; see InMemoryAssembly).
  bool can_add(const Rect& rect, SampleRange samples) const;

  // Samples folded so far at a pixel (absolute image coordinates inside rect()).
  int samples(int x, int y) const { return samples_[index(x, y)]; }

  // The image of the samples folded so far, in rect() with aovs(); a pixel with none yet is
  // what TileBuffer::reset leaves (0, depth +inf). Carries the sum of the folded passes' stats.
  void resolve(TileBuffer& out) const;
  TileBuffer resolve() const;

  const RenderStats& stats() const { return stats_; }

 private:
  // The first pixel of `overlap` (inside rect()) that does not hold exactly `count` samples.
  std::optional<std::pair<int, int>> first_not_at(const Rect& overlap, int count) const;
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y - rect_.y0) * static_cast<std::size_t>(rect_.width()) +
           static_cast<std::size_t>(x - rect_.x0);
  }

  Rect rect_;
  AovSet aovs_;
  RenderStats stats_;
  std::vector<int> samples_;
  std::vector<glm::dvec4> mean_;      // RGB and A
  std::vector<glm::dvec3> variance_;  // of the mean, per colour channel; with Aov::Variance only
  TileBuffer first_;                  // the first-sample AOVs (its RGBA is unused)
};

}  // namespace farm
