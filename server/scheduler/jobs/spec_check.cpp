#include "server/scheduler/jobs/spec_check.h"

#include <fmt/format.h>

#include "renderer/job/scene_builder.h"
#include "renderer/util/input_error.h"
#include "server/common/scene_hash.h"
#include "server/common/scene_materializer.h"
#include "server/common/service_error.h"
#include "server/common/video_encoder.h"
#include "server/scheduler/options/submit_limits.h"

namespace farm {

SpecCheck::SpecCheck(const SchedulerOptions& options, const AssetStore& assets)
    : options_(options),
      assets_(assets),
      scene_checker_(options.scene_check_program.empty()
                         ? nullptr
                         : std::make_unique<SceneChecker>(
                               options.scene_check_program,
                               SceneBudget{options.limits.max_scene_memory,
                                           std::chrono::milliseconds(static_cast<std::int64_t>(
                                               options.limits.max_scene_seconds * 1000.0)),
                                           options.limits.max_scene_checks})) {}

ValidatedJob SpecCheck::check(const v1::JobSpec& spec) const {
  check_spec_limits(spec, options_.limits);
  validate_asset_refs(spec);
  if (auto missing = missing_assets(spec, assets_); !missing.empty()) {
    throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                       fmt::format("{} on the scheduler (upload with UploadAsset first)",
                                   MissingAssetsError(missing).what()));
  }
  ValidatedJob out;
  out.spec = spec;
  out.scene_hash = scene_hash(spec);
  MaterializedScene m = materialize_scene(spec, out.scene_hash, assets_, options_.data_dir);
  check_job_limits(m.job, spec, options_.limits);
  const std::string shown_name = spec.file_name().empty() ? m.job.name : spec.file_name();
  if (!m.job.output.video.empty()) {
    // Refused now rather than failed after every frame is rendered.
    if (const FfmpegLookup ffmpeg = find_ffmpeg(); !ffmpeg) {
      throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                         fmt::format("{}: output.video: this scheduler cannot make videos: {}", shown_name,
                                     ffmpeg.problem));
    }
  }
  try {
    // What `farm render` does before rendering: models load, the scene builds. A server does it in
    // a child process under a budget; the merge's Embree check then loads the scene when it runs.
    if (scene_checker_) {
      scene_checker_->check(out.scene_hash, m.job_file, m.dir, shown_name);
    } else {
      LoadedScene loaded = load_job_scene(m.job);
      if (options_.validated_scene) {
        options_.validated_scene(out.scene_hash, m.job, std::move(loaded.scene), std::move(loaded.models));
      } else if (m.job.embree_rays > 0) {
        out.scene = std::make_shared<const PreparedScene>(std::move(loaded.scene));  // for the merge's check
      }
    }
  } catch (const InputError& e) {
    throw InputError(without_scene_folder(e.what(), m.dir));
  }
  out.job = std::make_shared<const Job>(std::move(m.job));
  return out;
}

}  // namespace farm
