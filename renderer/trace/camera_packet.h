#pragma once
// A pixel's camera rays traced together before its samples are shaded one by one in sample
// order (docs/architecture.md 8.6, "Packets"): rays through one pixel are as coherent as rays
// get, so they walk the BVH as one packet (SceneIntersector::closest_hit_packet), and each
// sample then reads its ray's hit instead of tracing it. The hits are closest_hit's bit for bit,
// so the image is the one the samples traced alone made.
#include <array>

#include "renderer/accel/scene_intersector.h"
#include "renderer/geometry/ray.h"

namespace farm {

// A camera ray's hit found beforehand, or none: then the tracer traces the ray itself.
struct CameraRayHit {
  bool traced = false;  // found beforehand: `hit` says what was met
  bool met = false;
  const SurfaceHit* hit = nullptr;
};

class CameraPacket {
 public:
  static constexpr int kWidth = 8;

  Ray& ray(int lane) { return rays_[static_cast<std::size_t>(lane)]; }
  const Ray& ray(int lane) const { return rays_[static_cast<std::size_t>(lane)]; }

  // Traces rays 0 .. count - 1 (at most kWidth), set beforehand through ray(), when they fill
  // the packet. Fewer are left to the tracer, ray by ray: a packet's walk tests every child box
  // against all its lanes, so a part-filled one costs more a ray than single rays do (Whitted's
  // 4 samples a pixel over the 100-cow grid: 11% more instructions, callgrind).
  void trace(const SceneIntersector& intersector, int count) {
    traced_ = count == kWidth;
    if (traced_) met_ = intersector.closest_hit_packet(rays_.data(), (1u << kWidth) - 1u, hits_.data());
  }

  // The ray's hit, or none (traced = false) when the packet was not traced.
  CameraRayHit hit(int lane) const {
    if (!traced_) return {};
    const bool met = (met_ >> lane & 1u) != 0;
    return {true, met, met ? &hits_[static_cast<std::size_t>(lane)] : nullptr};
  }

 private:
  std::array<Ray, kWidth> rays_;
  std::array<SurfaceHit, kWidth> hits_;
  unsigned met_ = 0;
  bool traced_ = false;
};

}  // namespace farm
