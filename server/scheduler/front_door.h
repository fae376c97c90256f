#pragma once
// The scheduler's one authorised front door: every operation a client may perform, for a caller
// already authenticated (a Principal), with the role and ownership checks inside. The transports
// are thin adapters over it and never reach around it: SchedulerService (farm.v1.Scheduler over
// gRPC, scheduler_service.h) and DashboardServer (the JSON API and /metrics over HTTP,
// http/dashboard_server.h). Each adapter turns its request into a Principal (AccessControl, whose
// tokens access() holds) and keeps only what is its own: streaming, pages, sessions.
//
// Who may do what (the roles of server/common/access_roles.h):
//   submit, plan_submission, upload_asset,     submit, admin
//   has_assets
//   get_job, watch_job, result_file,           submit (own jobs), read, admin
//   live_preview, job_log
//   list_jobs, watch_every_job                 submit (lists and hears only its own jobs), read, admin
//   cancel_job, pause_job, set_priority,       submit (own jobs), admin
//   retry_job, delete_job, set_job_limits,
//   add_dependencies (and the jobs waited for: read by the caller)
//   list_workers, metrics                      read, admin
//   register_worker, heartbeat                 worker (only for the workers it registered), admin
//   asset_file                                 worker (assets of the calls it has been given), admin
// A priority above max_priority needs admin (submit, set_priority).
// Refusals are ServiceError PERMISSION_DENIED naming the caller and what it asked (access_control.h);
// an unknown job is NOT_FOUND, a bad argument InputError.
//
// Lock: mutex_ guards the registered workers and who registered them; a leaf, held only while
// they are read or written (the core is called with it released). plans_, a semaphore, bounds the
// submissions planned at once (each holds one model's bytes); nothing is locked under it.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <semaphore>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "proto/farm.pb.h"
#include "server/common/access_control.h"
#include "server/common/asset_store.h"
#include "server/common/client_identity.h"
#include "server/scheduler/assets/asset_quota.h"
#include "server/scheduler/dispatch/unit_metrics.h"
#include "server/scheduler/asset_upload.h"
#include "server/scheduler/job_watch.h"
#include "server/scheduler/store/job_records.h"

namespace farm {

class SchedulerCore;
class JobEventQueue;

inline constexpr int kDefaultMaxPriority = 100;

// Who may call the scheduler, and how it calls the workers that register with it.
struct SchedulerAccess {
  AccessControl access;             // default: every caller holds every role
  ClientIdentity worker_identity;   // token and TLS for calls to registered workers
  int max_priority = kDefaultMaxPriority;
};

// What /metrics shows (http/prometheus_text.h).
struct SchedulerMetrics {
  JobRecords::Counts jobs;              // jobs by state, paused, units queued
  std::vector<v1::WorkerInfo> workers;  // as list_workers answers
  UnitMetrics::Snapshot units;          // units kept and failed, their rate and latency
};


class SchedulerFrontDoor {
 public:
  explicit SchedulerFrontDoor(SchedulerCore& core, SchedulerAccess access = {});
  SchedulerFrontDoor(const SchedulerFrontDoor&) = delete;
  SchedulerFrontDoor& operator=(const SchedulerFrontDoor&) = delete;

  // The tokens the adapters authenticate their callers with.
  const AccessControl& access() const { return access_.access; }
  // How long an upload stream may stay silent before its adapter ends it (--upload-idle-timeout).
  std::chrono::milliseconds upload_idle_timeout() const;

  // ---- Jobs ------------------------------------------------------------------------------------
  // SchedulerCore::submit, the job recorded as the caller's, weighted in fair share by its token's
  // weight. Each job it waits for (after, after_any, after_frames) must be one the caller may see.
  v1::Job submit(const Principal& who, const v1::SubmitJobRequest& request);
  v1::Job submit(const Principal& who, const v1::JobSpec& spec, int priority);
  v1::Job get_job(const Principal& who, const std::string& job_id) const;
  v1::ListJobsResponse list_jobs(const Principal& who, const v1::ListJobsRequest& request) const;
  // The job's events from now on (snapshot() is the job as it is now); `capacity` bounds the
  // events kept for a reader that falls behind (dropped()).
  std::unique_ptr<JobWatch> watch_job(const Principal& who, const std::string& job_id,
                                      std::size_t capacity = SIZE_MAX);
  // Every job's events from now on: a submitter hears only its own jobs'.
  std::unique_ptr<JobWatch> watch_every_job(const Principal& who, std::size_t capacity = SIZE_MAX);
  v1::Job cancel_job(const Principal& who, const std::string& job_id);
  v1::Job pause_job(const Principal& who, const std::string& job_id, bool paused);
  v1::Job set_priority(const Principal& who, const std::string& job_id, int priority);
  v1::Job set_job_limits(const Principal& who, const v1::SetJobLimitsRequest& request);
  v1::Job add_dependencies(const Principal& who, const v1::AddDependenciesRequest& request);
  v1::RetryJobResponse retry_job(const Principal& who, const std::string& job_id);
  v1::DeleteJobResponse delete_job(const Principal& who, const std::string& job_id);
  v1::GetJobLogResponse job_log(const Principal& who, const v1::GetJobLogRequest& request) const;
  // The file GetResult streams: a merged frame, a preview, a progressive preview or the video.
  std::filesystem::path result_file(const Principal& who, const v1::GetResultRequest& request) const;
  // The image of a frame as rendered so far (the job's first frame when none is given).
  // ServiceError NOT_FOUND when nothing of it is rendered yet.
  std::filesystem::path live_preview(const Principal& who, const std::string& job_id, std::optional<int> frame);

  // ---- Workers and metrics -----------------------------------------------------------------------
  v1::ListWorkersResponse list_workers(const Principal& who) const;
  // The figures of /metrics. They name the workers, so they ask what list_workers does.
  SchedulerMetrics metrics(const Principal& who) const;
  // A worker at the request's address added as the caller's; one registered there before (a
  // restart) is removed with its calls. PERMISSION_DENIED when another caller registered it.
  v1::RegisterWorkerResponse register_worker(const Principal& who, const v1::RegisterWorkerRequest& request);
  // Only for a worker this caller registered: a worker token cannot keep another's worker alive.
  v1::HeartbeatResponse heartbeat(const Principal& who, const v1::HeartbeatRequest& request);

  // ---- Assets ------------------------------------------------------------------------------------
  // An upload the caller may make (the header comes next: AssetUpload::begin).
  AssetUpload upload_asset(const Principal& who);
  v1::HasAssetsResponse has_assets(const Principal& who, const v1::HasAssetsRequest& request) const;
  // Which files the job needs that the request does not describe, and which of its assets to
  // upload (jobs/submission_plan.h): what a client asks before submit.
  v1::PlanSubmissionResponse plan_submission(const Principal& who, const v1::PlanSubmissionRequest& request) const;
  // The blob GetAsset streams. ServiceError NOT_FOUND when the store does not hold it.
  std::filesystem::path asset_file(const Principal& who, const std::string& sha256) const;

 private:
  // The job `job_id` if `who` may see it: its owner, or a caller holding `any_job` roles.
  // ServiceError NOT_FOUND or PERMISSION_DENIED.
  v1::Job visible_job(const Principal& who, const std::string& job_id, Roles any_job, const char* action) const;
  // `job` (as read for `job_id`) when `who` may see it: NOT_FOUND when empty, PERMISSION_DENIED
  // for another owner's job without one of `any_job`.
  v1::Job visible(const Principal& who, std::optional<v1::Job> job, const std::string& job_id, Roles any_job,
                  const char* action) const;
  // Refuses a caller without admin a priority above max_priority (`what`: the action, for the message).
  // The jobs a job is to wait for, each one the caller may see (NOT_FOUND or PERMISSION_DENIED
  // naming it) and at most kMaxDependencies.
  void check_dependencies(const Principal& who, const std::vector<std::string>& after,
                          const std::vector<std::string>& after_any) const;
  void check_priority(const Principal& who, int priority, const char* what) const;

  struct Registered {
    std::string worker_id;
    std::string principal;  // the name of the caller that registered it
  };

  // Plans read whole models in this process (jobs/submission_plan.h): as many at once as scene
  // checks (--max-scene-checks), so that submitters cannot make it hold many large files together.
  static constexpr std::ptrdiff_t kMaxPlansAtOnce = 64;

  SchedulerCore& core_;
  const SchedulerAccess access_;
  mutable std::counting_semaphore<kMaxPlansAtOnce> plans_;
  std::mutex mutex_;
  std::map<std::string, Registered> registered_;  // by worker address
  // Who registered each worker id now in registered_: a heartbeat, every second from every
  // worker, finds its registrant in one look-up.
  std::map<std::string, std::string> registrant_of_;
};

}  // namespace farm
