#pragma once
// A tile's camera rays traced ahead of their shading, a packet of eight at a time
// (docs/architecture.md 8.6, "Packets"): the rays are made in the very order the tile's samples
// are shaded (rows top to bottom, each row left to right, each pixel's samples in order), eight
// in a row walk the BVH together (SceneIntersector::closest_hit_packet), and each sample then
// reads its ray's hit instead of tracing it. Neighbouring pixels' rays are nearly as coherent as
// one pixel's, so packets fill whatever the sample count (Whitted's 4 a pixel, a pass of 1). The
// hits are closest_hit's bit for bit, so the image is the one the samples traced alone made.
#include <array>

#include "renderer/accel/scene_intersector.h"
#include "renderer/geometry/ray.h"
#include "renderer/image/tile_buffer.h"  // Rect

namespace farm {

// A camera ray's hit found beforehand, or none: then the tracer traces the ray itself.
struct CameraRayHit {
  bool traced = false;  // found beforehand: `hit` says what was met
  bool met = false;
  const SurfaceHit* hit = nullptr;
};

class CameraRayStream {
 public:
  static constexpr int kWidth = 8;

  // Samples [first, end) of each pixel of `tile`.
  CameraRayStream(const Rect& tile, int first, int end)
      : tile_(tile), first_(first), end_(end), x_(tile.x0), y_(tile.y0), sample_(first) {
    if (first_ >= end_) y_ = tile_.y1;  // no samples: nothing to stream
  }

  // Whether the rays made so far are used up: the next sample needs refill first.
  bool used_up() const { return taken_ == count_; }

  // Makes the next rays, up to kWidth, as ray_of(x, y, sample) in the order above, and traces
  // them as a packet when they fill one. Fewer (the tile's last) are left to the tracer, ray by
  // ray: a packet's walk tests every child box against all its lanes, so a part-filled one costs
  // more a ray than single rays do (4 rays a packet over the 100-cow grid: 11% more
  // instructions, callgrind).
  template <typename RayOf>
  void refill(const SceneIntersector& intersector, RayOf&& ray_of) {
    count_ = 0;
    taken_ = 0;
    for (; count_ < kWidth && y_ < tile_.y1; ++count_) {
      rays_[static_cast<std::size_t>(count_)] = ray_of(x_, y_, sample_);
      if (++sample_ < end_) continue;
      sample_ = first_;
      if (++x_ < tile_.x1) continue;
      x_ = tile_.x0;
      ++y_;
    }
    met_ = traced() ? intersector.closest_hit_packet(rays_.data(), (1u << kWidth) - 1u, hits_.data()) : 0u;
  }

  // The next sample's lane in the rays made by the last refill.
  int take() { return taken_++; }

  const Ray& ray(int lane) const { return rays_[static_cast<std::size_t>(lane)]; }
  // Whether the last refill traced its rays (it made kWidth of them).
  bool traced() const { return count_ == kWidth; }
  // The ray's hit, or none (traced = false) when the rays were not traced.
  CameraRayHit hit(int lane) const {
    if (!traced()) return {};
    const bool met = (met_ >> lane & 1u) != 0;
    return {true, met, met ? &hits_[static_cast<std::size_t>(lane)] : nullptr};
  }

 private:
  const Rect tile_;
  const int first_, end_;
  int x_, y_, sample_;  // the next ray's pixel and sample
  std::array<Ray, kWidth> rays_;
  std::array<SurfaceHit, kWidth> hits_;
  int count_ = 0, taken_ = 0;
  unsigned met_ = 0;
};

}  // namespace farm
