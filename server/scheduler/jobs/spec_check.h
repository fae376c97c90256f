#pragma once
// A JobSpec from outside (SubmitJob, or `farm render` handing its embedded farm a spec) checked
// as `farm render` checks a job before it renders, and made a ValidatedJob: the one value the
// scheduler queues (validated_job.h). What a request may start is checked before it starts
// anything: the text before it is parsed, the units, samples and rays before a model is loaded.
#include <memory>

#include "proto/farm.pb.h"
#include "server/common/asset_store.h"
#include "server/scheduler/jobs/scene_check.h"
#include "server/scheduler/jobs/validated_job.h"
#include "server/scheduler/options/scheduler_options.h"

namespace farm {

class SpecCheck {
 public:
  // `options` and `assets` outlive it. With options.scene_check_program set, the models load in a
  // child process under a budget (scene_check.h); otherwise here.
  SpecCheck(const SchedulerOptions& options, const AssetStore& assets);

  // The spec, its limits, its assets (each present and the size it says), the job parsed with
  // them laid out under data_dir/scenes/<hash>, its models loaded and its scene built. Throws
  // ServiceError FAILED_PRECONDITION naming a missing asset (or ffmpeg missing for a video),
  // InputError for a bad job (naming the job file and the JSON path, never the scheduler's own
  // folders), ServiceError RESOURCE_EXHAUSTED when the scene check's budget ran out.
  ValidatedJob check(const v1::JobSpec& spec) const;

 private:
  const SchedulerOptions& options_;
  const AssetStore& assets_;
  std::unique_ptr<SceneChecker> scene_checker_;  // when options_.scene_check_program is set
};

}  // namespace farm
