#pragma once
// Float pixels of one rectangle of the frame: RGBA always, AOVs when asked. A whole frame (the
// film) is simply a TileBuffer whose rect is the full image.
#include <cstdint>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <limits>
#include <vector>

#include "renderer/image/aov.h"
#include "renderer/util/uninitialized_array.h"

namespace farm {

struct Rect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // half-open: [x0, x1) x [y0, y1)

  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
  Rect intersect(const Rect& o) const;
  bool operator==(const Rect&) const = default;
};

// Work counters that travel with a tile and add up when tiles are merged.
struct RenderStats {
  std::uint64_t fragments = 0;        // rasterizer: samples that passed the coverage test
  std::uint64_t samples = 0;          // path tracer: camera samples traced
  std::uint64_t invalid_samples = 0;  // path tracer: samples that came out NaN or inf (dropped)
  std::uint64_t rays = 0;             // ray engines: rays traced (closest-hit and shadow)

  RenderStats& operator+=(const RenderStats& o) {
    fragments += o.fragments;
    samples += o.samples;
    invalid_samples += o.invalid_samples;
    rays += o.rays;
    return *this;
  }
};

class TileBuffer {
 public:
  TileBuffer() = default;
  TileBuffer(const Rect& rect, const AovSet& aovs) { reset(rect, aovs); }

  // Resizes to `rect` and clears: colour and alpha 0, depth +inf, other AOVs 0.
  void reset(const Rect& rect, const AovSet& aovs);
  // Resizes to `rect` leaving the pixels unspecified, for a film that tiles will cover
  // completely: nothing is cleared only to be overwritten, and the pages are first touched by
  // the threads that paste into them.
  void reset_for_overwrite(const Rect& rect, const AovSet& aovs);

  // What a render that was stopped leaves: no pixels (an empty rect, so that nothing half-written
  // can be pasted, merged or sent), only the stats of the work it did.
  void discard_pixels();

  const Rect& rect() const { return rect_; }
  const AovSet& aovs() const { return aovs_; }

  // Pixel coordinates are absolute image coordinates inside rect().
  glm::vec4& rgba(int x, int y) { return rgba_[index(x, y)]; }
  const glm::vec4& rgba(int x, int y) const { return rgba_[index(x, y)]; }
  float& depth(int x, int y) { return depth_[index(x, y)]; }
  float depth(int x, int y) const { return depth_[index(x, y)]; }
  glm::vec3& normal(int x, int y) { return normal_[index(x, y)]; }
  const glm::vec3& normal(int x, int y) const { return normal_[index(x, y)]; }
  glm::vec3& albedo(int x, int y) { return albedo_[index(x, y)]; }
  const glm::vec3& albedo(int x, int y) const { return albedo_[index(x, y)]; }
  float& bvh_cost(int x, int y) { return bvh_cost_[index(x, y)]; }
  float bvh_cost(int x, int y) const { return bvh_cost_[index(x, y)]; }
  // Per channel, the variance of the pixel's mean estimate (Aov::Variance).
  glm::vec3& variance(int x, int y) { return variance_[index(x, y)]; }
  const glm::vec3& variance(int x, int y) const { return variance_[index(x, y)]; }

  RenderStats& stats() { return stats_; }
  const RenderStats& stats() const { return stats_; }

  // Copies the pixels of the overlap of `tile` into this buffer (the merge step); AOVs this buffer
  // lacks are skipped. Stats are not touched: callers add them up, so that pastes of disjoint
  // tiles may run concurrently.
  void paste(const TileBuffer& tile);

  static constexpr float kNoDepth = std::numeric_limits<float>::infinity();

 private:
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y - rect_.y0) * static_cast<std::size_t>(rect_.width()) +
           static_cast<std::size_t>(x - rect_.x0);
  }

  Rect rect_;
  AovSet aovs_;
  RenderStats stats_;
  UninitializedArray<glm::vec4> rgba_;
  UninitializedArray<float> depth_;
  UninitializedArray<glm::vec3> normal_;
  UninitializedArray<glm::vec3> albedo_;
  UninitializedArray<float> bvh_cost_;
  UninitializedArray<glm::vec3> variance_;
};

}  // namespace farm
