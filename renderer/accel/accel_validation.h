#pragma once
// Checks one SceneIntersector against another (ours against Embree) on a deterministic set of
// rays: primary rays through the image plus random secondary rays (origins in the scene's
// bounds, directions uniform on the sphere).
#include <cstdint>
#include <string>

#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"
#include "renderer/job/render_settings.h"

namespace farm {

struct AccelValidation {
  std::uint64_t rays = 0;
  std::uint64_t hit_miss_disagreements = 0;   // one hit, the other missed
  // Both hit, different (object, triangle) and t more than 1e-5 apart (relative, as below):
  // closer than that it is one point on an edge or vertex that two triangles share, a tie.
  std::uint64_t triangle_disagreements = 0;
  // |t_ours - t_ref| / max(|t_ref|, D / |direction|), D the diagonal of the scene's bounds: the
  // difference relative to the hit distance, or to the scene's size for hits nearer than that
  // (float noise in t scales with the coordinates, not with t). Over the rays both hit, except
  // those counted as triangle disagreements (their t difference would only repeat that count).
  double max_relative_t_difference = 0.0;
  double mean_relative_t_difference = 0.0;

  std::string summary() const;  // one line for the render summary and `farm validate`
};

// `rays` rays: half primary (through a jittered pixel grid of the settings' image), half
// secondary; the same rays for the same (scene, settings, rays, seed).
AccelValidation validate_accel(const PreparedScene& scene, const RenderSettings& settings,
                               const SceneIntersector& ours, const SceneIntersector& reference,
                               std::uint64_t rays);

// What a job's validate.embree_rays and `farm validate` run.
inline constexpr std::uint64_t kDefaultValidationRays = 100000;
// Hit/miss disagreements tolerated before validation fails: 0.001% of the rays.
inline constexpr double kHitMissTolerance = 1e-5;

// The accel compared with Embree when the job's own is `accel`: Embree is compared with `bvh`.
AccelKind accel_to_validate(AccelKind accel);

// Compares `accel` (the scene's cached intersector, so a render's BVHs are reused) with Embree
// on `rays` rays.
AccelValidation validate_against_embree(const PreparedScene& scene, const RenderSettings& settings,
                                        AccelKind accel, std::uint64_t rays);

bool validation_passes(const AccelValidation& v);

}  // namespace farm
