#pragma once
// PlanSubmission (proto/farm.proto): which files a job needs, told by the scheduler, so that no
// client reads model formats. The job is read from its text as it will be laid out (parse_job with
// its models resolved by name under the job's folder, JobLoadOptions::models_by_name), and each
// model it holds, and each material library such a model names, is read for the files it
// references by the scanner `farm submit` uses (server/common/model_references.h); here a
// reference is resolved by name in the job's folder, never on this machine's disk.
//
// Checked as SubmitJob checks a spec before any work (check_spec_limits, validate_asset_refs, the
// blobs' sizes); a bad job is an InputError naming the file and the JSON path as SubmitJob's; a
// reference that is absolute or leads out of the job's folder one naming the model and the
// reference. Bounded: only the spec's assets are read, each at most once a call, each within the
// asset limits; the files asked for, with the assets and the absent ones, at most kMaxJobAssets.
#include "proto/farm.pb.h"
#include "server/common/asset_store.h"
#include "server/scheduler/options/submit_limits.h"

namespace farm {

v1::PlanSubmissionResponse plan_submission(const v1::PlanSubmissionRequest& request, const AssetStore& store,
                                           const SubmitLimits& limits);

}  // namespace farm
