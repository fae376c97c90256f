#include "server/cli/validate_command.h"

#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include "renderer/accel/embree_intersector.h"
#include "renderer/accel/scene_intersector.h"
#include "renderer/job/job_limits.h"
#include "renderer/job/scene_builder.h"
#include "server/cli/job_file_options.h"

namespace farm {

int run_validate_command(const ValidateCommandOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Job job = load_job(options.job_file, options.load);
  AccelKind accel = accel_to_validate(job.render.accel);
  if (options.accel) {
    const auto chosen = accel_from_string(*options.accel);
    if (!chosen || *chosen == AccelKind::Embree) {
      throw InputError(fmt::format("--accel: expected bvh, bvh-median or naive, not '{}'",
                                   *options.accel));
    }
    accel = *chosen;
  }
  const std::uint64_t rays =
      options.rays ? *options.rays
                   : (job.embree_rays > 0 ? static_cast<std::uint64_t>(job.embree_rays)
                                          : kDefaultValidationRays);

  const PreparedScene prepared(build_scene(job));
  const RenderSettings& r = job.render;
  fmt::print("job '{}': {} triangles in {} object(s); {} vs embree on {} rays ({} primary at "
             "{}x{}, {} from inside the scene's bounds)\n",
             job.name, prepared.triangle_count(), prepared.objects().size(), to_string(accel), rays,
             rays / 2, r.width, r.height, rays - rays / 2);
  const AccelValidation result = validate_against_embree(prepared, r, accel, rays);
  fmt::print("{}\n", result.summary());
  const bool passes = validation_passes(result);
  fmt::print("{}: {} hit/miss disagreements, {} tolerated (0.001% of rays); {:.1f} ms in all\n",
             passes ? "agree" : "DISAGREE", result.hit_miss_disagreements,
             static_cast<std::uint64_t>(kHitMissTolerance * static_cast<double>(rays)),
             std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                 .count());
  return passes ? 0 : 1;
}

void add_validate_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<ValidateCommandOptions>();
  CLI::App* validate = app.add_subcommand(
      "validate", "Compare our acceleration structure's ray hits with Embree's on a job's scene");
  add_job_file_options(*validate, o->job_file, o->load);
  validate->add_option("--rays", o->rays,
                       "Rays to compare, half primary and half from inside the scene "
                       "(default: the job's validate.embree_rays, else 100000)")
      ->check(CLI::Range(std::uint64_t{1}, static_cast<std::uint64_t>(kMaxEmbreeRays)));
  validate->add_option("--accel", o->accel,
                       "Ours to compare: bvh, bvh-median or naive (default: the job's render.accel; "
                       "bvh when that is embree)")
      ->check(CLI::IsMember({"bvh", "bvh-median", "naive"}));
  validate->footer("Exit codes: 0 the hits agree (hit/miss disagreements at most 0.001% of the "
                   "rays), 1 they do not (or an internal error), 2 bad input.");
  commands.add(validate, [o] { return run_validate_command(*o); });
}

}  // namespace farm
