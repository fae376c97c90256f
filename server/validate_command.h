#pragma once
// `farm validate JOB`: checks our acceleration structure against Embree on the job's scene, and
// the same check that `farm render` runs when a job asks for validate.embree_rays.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "renderer/geometry/accel_validation.h"
#include "renderer/prepared_scene.h"
#include "renderer/scene/input_error.h"
#include "renderer/scene/job.h"

namespace farm {

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

struct ValidateCommandOptions {
  std::filesystem::path job_file;
  JobLoadOptions load;
  std::optional<std::string> accel;   // bvh, bvh-median or naive; default: the job's
  std::optional<std::uint64_t> rays;  // default: validate.embree_rays, else 100000
};

// Prints the comparison and returns the exit code: 0 when the hits agree within the tolerance,
// 1 when they do not. Throws InputError for bad input.
int run_validate_command(const ValidateCommandOptions& options);

}  // namespace farm
