#include "server/scheduler/front_door.h"

#include <fmt/format.h>

#include <algorithm>
#include <thread>

#include "renderer/job/job_limits.h"
#include "renderer/job/worker_requirements.h"
#include "renderer/util/input_error.h"
#include "renderer/util/utf8_text.h"
#include "server/common/hex.h"
#include "server/common/network_address.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"
#include "server/scheduler/jobs/submission_plan.h"
#include "server/scheduler/scheduler_core.h"

namespace farm {

namespace {

constexpr int kDefaultPageSize = 50;
constexpr int kMaxPageSize = 1000;
constexpr std::size_t kMaxNameFilterBytes = 256;
constexpr int kMaxLogPage = 1000;  // job_log's entries a page

const Roles kJobSubmitters = Role::submit | Role::admin;
const Roles kJobReaders = Role::submit | Role::read | Role::admin;
const Roles kAllJobReaders = Role::read | Role::admin;
const Roles kWorkers = Role::worker | Role::admin;

// How long a plan waits for one of the others to end before it is refused.
constexpr auto kPlanWait = std::chrono::seconds(30);

// Plans at once: the scene checks' number (0: half the hardware threads, at least 1).
std::ptrdiff_t plans_at_once(const SubmitLimits& limits, std::ptrdiff_t most) {
  const int n = limits.max_scene_checks > 0 ? limits.max_scene_checks
                                            : static_cast<int>(std::thread::hardware_concurrency() / 2);
  return std::clamp<std::ptrdiff_t>(n, 1, most);
}

// What a registering worker says of itself, bounded: it is shown, never trusted.
WorkerFacts facts_of(const v1::RegisterWorkerRequest& r) {
  constexpr int kMaxEngines = 8;
  constexpr std::size_t kMaxText = 64;
  WorkerFacts f;
  f.threads = r.threads();  // register_worker refused one outside [0, kMaxThreads]
  for (int i = 0; i < std::min(r.engines_size(), kMaxEngines); ++i) f.engines.push_back(utf8_prefix(r.engines(i), kMaxText));
  f.hostname = utf8_prefix(r.hostname(), 255);
  f.version = utf8_prefix(r.version(), kMaxText);
  // Checked by register_worker; sorted, each once, for the jobs' requirements to be matched.
  f.tags.assign(r.tags().begin(), r.tags().end());
  sort_worker_tags(f.tags);
  return f;
}

}  // namespace

// ---- The front door --------------------------------------------------------------------------------

SchedulerFrontDoor::SchedulerFrontDoor(SchedulerCore& core, SchedulerAccess access)
    : core_(core), access_(std::move(access)), plans_(plans_at_once(core.options().limits, kMaxPlansAtOnce)) {}

std::chrono::milliseconds SchedulerFrontDoor::upload_idle_timeout() const {
  return core_.options().upload_idle_timeout;
}

v1::Job SchedulerFrontDoor::visible_job(const Principal& who, const std::string& job_id, Roles any_job,
                                        const char* action) const {
  return visible(who, core_.get_job(job_id), job_id, any_job, action);
}

v1::Job SchedulerFrontDoor::visible(const Principal& who, std::optional<v1::Job> job, const std::string& job_id,
                                    Roles any_job, const char* action) const {
  if (!job) throw ServiceError(grpc::StatusCode::NOT_FOUND, fmt::format("no job '{}'", job_id.substr(0, 80)));
  if (!who.roles.any_of(any_job) && job->owner() != who.name) {
    deny(who, fmt::format("{} job {}: it belongs to '{}'", action, job_id, job->owner()));
  }
  return std::move(*job);
}

void SchedulerFrontDoor::check_priority(const Principal& who, int priority, const char* what) const {
  if (priority > access_.max_priority && !who.roles.has(Role::admin)) {
    deny(who, fmt::format("{} with priority {} (above {} needs the admin role)", what, priority, access_.max_priority));
  }
}

void SchedulerFrontDoor::check_dependencies(const Principal& who, const std::vector<std::string>& after,
                                            const std::vector<std::string>& after_any) const {
  if (after.size() + after_any.size() > kMaxDependencies) {
    throw InputError(fmt::format("a job may wait for at most {} jobs, not {}", kMaxDependencies,
                                 after.size() + after_any.size()));
  }
  for (const std::vector<std::string>* ids : {&after, &after_any}) {
    for (const std::string& id : *ids) visible_job(who, id, kAllJobReaders, "wait for");
  }
}

namespace {

JobCaps caps_of(std::uint32_t max_workers, std::uint32_t max_units_in_flight) {
  for (std::uint32_t n : {max_workers, max_units_in_flight}) {
    if (n > static_cast<std::uint32_t>(kMaxJobCap)) throw InputError(fmt::format("a cap of {}: at most {}", n, kMaxJobCap));
  }
  return {static_cast<int>(max_workers), static_cast<int>(max_units_in_flight)};
}

}  // namespace

v1::Job SchedulerFrontDoor::submit(const Principal& who, const v1::SubmitJobRequest& request) {
  AccessControl::check(who, kJobSubmitters, "SubmitJob");
  check_priority(who, request.priority(), "submit");
  QueueTerms terms;
  terms.after.assign(request.after().begin(), request.after().end());
  terms.after_any.assign(request.after_any().begin(), request.after_any().end());
  terms.after_frames = request.after_frames();
  check_dependencies(who, terms.after, terms.after_any);
  if (!terms.after_frames.empty()) check_dependencies(who, {terms.after_frames}, {});
  terms.caps = caps_of(request.max_workers(), request.max_units_in_flight());
  terms.owner_weight_milli = who.share_weight_milli;
  v1::Job job = core_.submit(core_.check(request.job()), request.priority(), nullptr, who.name, terms);
  core_.explain_placement({&job, 1});
  return job;
}

v1::Job SchedulerFrontDoor::submit(const Principal& who, const v1::JobSpec& spec, int priority) {
  v1::SubmitJobRequest request;
  *request.mutable_job() = spec;
  request.set_priority(priority);
  return submit(who, request);
}

v1::Job SchedulerFrontDoor::get_job(const Principal& who, const std::string& job_id) const {
  AccessControl::check(who, kJobReaders, "GetJob");
  return visible_job(who, job_id, kAllJobReaders, "see");
}

v1::ListJobsResponse SchedulerFrontDoor::list_jobs(const Principal& who, const v1::ListJobsRequest& request) const {
  AccessControl::check(who, kJobReaders, "ListJobs");
  int size = request.page_size() <= 0 ? kDefaultPageSize : std::min(request.page_size(), kMaxPageSize);
  std::int64_t before = 0;
  if (!request.page_token().empty()) {
    try {
      before = std::stoll(request.page_token());
    } catch (const std::exception&) {
      throw InputError(fmt::format("page_token '{}' is not one ListJobs returned",
                                   request.page_token().substr(0, 40)));
    }
  }
  JobFilter filter;
  for (int s : request.states()) filter.states.push_back(static_cast<v1::JobState>(s));
  if (!who.roles.any_of(kAllJobReaders)) filter.owner = who.name;  // a submitter lists its own jobs
  if (request.name().size() > kMaxNameFilterBytes) {
    throw InputError(fmt::format("ListJobs: name filter of {} bytes (at most {})", request.name().size(),
                                 kMaxNameFilterBytes));
  }
  filter.name = request.name();
  if (request.id_prefix().size() > 64 || !is_lowercase_hex(request.id_prefix())) {
    throw InputError(fmt::format("ListJobs: id_prefix '{}' is not the start of a job id (lowercase hex)",
                                 request.id_prefix().substr(0, 64)));
  }
  filter.id_prefix = request.id_prefix();
  auto [jobs, next] = core_.store().jobs().list_jobs(filter, size, before);
  v1::ListJobsResponse response;
  core_.explain_placement(jobs);
  for (v1::Job& job : jobs) *response.add_jobs() = std::move(job);
  if (next > 0) response.set_next_page_token(std::to_string(next));
  return response;
}

std::unique_ptr<JobWatch> SchedulerFrontDoor::watch_job(const Principal& who, const std::string& job_id,
                                                        std::size_t capacity) {
  AccessControl::check(who, kJobReaders, "WatchJob");
  // Subscribed and the snapshot read at one moment of the job's events, so none falls between
  // them and none in the queue is older than the snapshot (a watcher saw tiles_done go 4, 3, 4
  // when the snapshot was read after subscribing); a caller the snapshot then refuses is
  // unsubscribed on the way out.
  SchedulerCore::WatchStart start = core_.watch_from_now(job_id, capacity);
  std::unique_ptr<JobWatch> watch(new JobWatch(core_, job_id, std::move(start.queue), std::nullopt));
  watch->snapshot_ = visible(who, std::move(start.job), job_id, kAllJobReaders, "watch");
  watch->last_ = watch->snapshot_.state();
  return watch;
}

std::unique_ptr<JobWatch> SchedulerFrontDoor::watch_every_job(const Principal& who, std::size_t capacity) {
  AccessControl::check(who, kJobReaders, "WatchJob");
  // Every job's events are everyone's to hear only with read or admin; a submitter hears its own.
  std::optional<std::string> only_owner;
  if (!who.roles.any_of(kAllJobReaders)) only_owner = who.name;
  return std::unique_ptr<JobWatch>(
      new JobWatch(core_, JobEvents::kEveryJob, core_.watch(JobEvents::kEveryJob, capacity), std::move(only_owner)));
}

v1::Job SchedulerFrontDoor::cancel_job(const Principal& who, const std::string& job_id) {
  AccessControl::check(who, kJobSubmitters, "CancelJob");
  visible_job(who, job_id, Role::admin, "cancel");
  return core_.cancel(job_id, who.name);
}

v1::Job SchedulerFrontDoor::pause_job(const Principal& who, const std::string& job_id, bool paused) {
  AccessControl::check(who, kJobSubmitters, "PauseJob");
  visible_job(who, job_id, Role::admin, paused ? "pause" : "resume");
  return core_.pause(job_id, paused, who.name);
}

v1::Job SchedulerFrontDoor::set_priority(const Principal& who, const std::string& job_id, int priority) {
  AccessControl::check(who, kJobSubmitters, "SetPriority");
  visible_job(who, job_id, Role::admin, "re-prioritise");
  check_priority(who, priority, "re-prioritise");
  return core_.set_priority(job_id, priority, who.name);
}

v1::Job SchedulerFrontDoor::set_job_limits(const Principal& who, const v1::SetJobLimitsRequest& request) {
  AccessControl::check(who, kJobSubmitters, "SetJobLimits");
  visible_job(who, request.job_id(), Role::admin, "change the caps of");
  const JobCaps caps = caps_of(request.max_workers(), request.max_units_in_flight());
  return core_.set_caps(request.job_id(),
                        request.has_max_workers() ? std::optional<int>(caps.max_workers) : std::nullopt,
                        request.has_max_units_in_flight() ? std::optional<int>(caps.max_units_in_flight) : std::nullopt,
                        who.name);
}

v1::Job SchedulerFrontDoor::add_dependencies(const Principal& who, const v1::AddDependenciesRequest& request) {
  AccessControl::check(who, kJobSubmitters, "AddDependencies");
  visible_job(who, request.job_id(), Role::admin, "add dependencies to");
  const std::vector<std::string> after(request.after().begin(), request.after().end());
  const std::vector<std::string> after_any(request.after_any().begin(), request.after_any().end());
  if (after.empty() && after_any.empty()) {
    throw InputError("AddDependencies: name the jobs to wait for (after, after_any)");
  }
  check_dependencies(who, after, after_any);
  return core_.add_dependencies(request.job_id(), after, after_any, who.name);
}

v1::RetryJobResponse SchedulerFrontDoor::retry_job(const Principal& who, const std::string& job_id) {
  AccessControl::check(who, kJobSubmitters, "RetryJob");
  visible_job(who, job_id, Role::admin, "retry");
  RetriedJob r = core_.retry(job_id, who.name);
  v1::RetryJobResponse response;
  *response.mutable_job() = std::move(r.job);
  response.set_units_queued(r.units_queued);
  return response;
}

v1::DeleteJobResponse SchedulerFrontDoor::delete_job(const Principal& who, const std::string& job_id) {
  AccessControl::check(who, kJobSubmitters, "DeleteJob");
  visible_job(who, job_id, Role::admin, "delete");
  v1::DeleteJobResponse response;
  response.set_bytes_freed(core_.remove(job_id));
  response.set_job_id(job_id);
  return response;
}

v1::GetJobLogResponse SchedulerFrontDoor::job_log(const Principal& who, const v1::GetJobLogRequest& request) const {
  AccessControl::check(who, kJobReaders, "GetJobLog");
  visible_job(who, request.job_id(), kAllJobReaders, "read the log of");
  const int size = request.page_size() == 0
                       ? kMaxLogPage
                       : static_cast<int>(std::min<std::uint32_t>(request.page_size(), kMaxLogPage));
  bool more = false;
  v1::GetJobLogResponse response;
  for (v1::JobLogEntry& e : core_.store().log().job_log(request.job_id(), request.after(), size, &more)) {
    *response.add_entries() = std::move(e);
  }
  response.set_more(more);
  return response;
}

std::filesystem::path SchedulerFrontDoor::result_file(const Principal& who, const v1::GetResultRequest& request) const {
  AccessControl::check(who, kJobReaders, "GetResult");
  const v1::Job job = visible_job(who, request.job_id(), kAllJobReaders, "fetch");
  const bool preview = request.kind() == v1::RESULT_KIND_PREVIEW;
  const bool progressive = request.kind() == v1::RESULT_KIND_PROGRESSIVE;
  if (progressive && !request.has_frame()) {
    throw InputError("GetResult: a progressive preview is of a frame: give the frame");
  }
  std::optional<std::filesystem::path> file;
  if (request.kind() == v1::RESULT_KIND_VIDEO) {
    // The whole job's: made once every frame is done.
    if (request.has_frame()) {
      throw InputError(fmt::format("job {}: a video holds every frame; ask for it without a frame", job.job_id()));
    }
    if (job.state() != v1::JOB_STATE_SUCCEEDED) {
      throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                         fmt::format("job {} is {}, not done: its video is made once every frame is",
                                     job.job_id(), v1::JobState_Name(job.state())));
    }
    file = core_.video_file(job.job_id());
    if (!file) {
      throw ServiceError(grpc::StatusCode::NOT_FOUND,
                         fmt::format("job {} has no video (its job file gives no output.video)", job.job_id()));
    }
  } else if (request.has_frame()) {
    // A frame can be fetched as soon as it is merged, while the job renders its others.
    const int f = request.frame(), first = job.frame_first(), step = std::max(1, job.frame_step());
    if (f < first || f > job.frame_last() || (f - first) % step != 0) {
      throw InputError(fmt::format("job {} renders no frame {} (its frames are {} to {} by {})", job.job_id(), f,
                                   first, job.frame_last(), step));
    }
    if (job.state() != v1::JOB_STATE_FAILED && job.state() != v1::JOB_STATE_CANCELLED) {
      file = progressive ? core_.progressive_result(job.job_id(), f) : core_.result_file(job.job_id(), preview, f);
    }
    if (!file) {
      throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                         fmt::format("frame {} of job {} is not rendered yet (the job is {}, {} of {} frames done)",
                                     f, job.job_id(), v1::JobState_Name(job.state()), job.frames_done(),
                                     job.frames_total()));
    }
  } else {
    if (job.state() != v1::JOB_STATE_SUCCEEDED) {
      throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                         fmt::format("job {} is {}, not done", job.job_id(), v1::JobState_Name(job.state())));
    }
    file = core_.result_file(job.job_id(), preview);
    if (!file) throw ServiceError(grpc::StatusCode::INTERNAL, "the job's result file is missing");
  }
  return *file;
}

std::filesystem::path SchedulerFrontDoor::live_preview(const Principal& who, const std::string& job_id,
                                                       std::optional<int> frame) {
  const v1::Job job = get_job(who, job_id);
  const int f = frame.value_or(job.frame_first());
  const std::optional<std::filesystem::path> file = core_.live_preview(job_id, f);
  if (!file) throw ServiceError(grpc::StatusCode::NOT_FOUND, fmt::format("frame {} has nothing rendered yet", f));
  return *file;
}

v1::ListWorkersResponse SchedulerFrontDoor::list_workers(const Principal& who) const {
  AccessControl::check(who, kAllJobReaders, "ListWorkers");
  v1::ListWorkersResponse response;
  for (v1::WorkerInfo& w : core_.worker_infos()) *response.add_workers() = std::move(w);
  return response;
}

SchedulerMetrics SchedulerFrontDoor::metrics(const Principal& who) const {
  // The workers' table is in them: the roles of ListWorkers, named as it in a refusal.
  AccessControl::check(who, kAllJobReaders, "ListWorkers");
  return SchedulerMetrics{core_.store().jobs().counts(), core_.worker_infos(), core_.unit_metrics()};
}

v1::RegisterWorkerResponse SchedulerFrontDoor::register_worker(const Principal& who,
                                                               const v1::RegisterWorkerRequest& request) {
  AccessControl::check(who, kWorkers, "RegisterWorker");
  if (const std::string problem = worker_address_problem(request.address()); !problem.empty()) {
    throw InputError(fmt::format("RegisterWorker: address '{}': {}", utf8_prefix(request.address(), 80), problem));
  }
  if (request.threads() < 0 || request.threads() > kMaxThreads) {
    throw InputError(fmt::format("RegisterWorker: threads {}: give 0 (not known) to {}", request.threads(), kMaxThreads));
  }
  if (static_cast<std::size_t>(request.tags_size()) > kMaxWorkerTags) {
    throw InputError(fmt::format("RegisterWorker: {} tags; at most {}", request.tags_size(), kMaxWorkerTags));
  }
  for (const std::string& tag : request.tags()) {
    if (const std::optional<std::string> problem = worker_tag_problem(tag)) {
      throw InputError(fmt::format("RegisterWorker: tag: {}", *problem));
    }
  }
  std::string old;
  {
    std::lock_guard lock(mutex_);
    if (auto it = registered_.find(request.address()); it != registered_.end()) {
      if (it->second.principal != who.name && !who.roles.has(Role::admin)) {
        deny(who, fmt::format("register at {}: '{}' registered a worker there", request.address(),
                              it->second.principal));
      }
      old = it->second.worker_id;
    }
  }
  // A worker registering again at the same address restarted: its old calls are dead.
  if (!old.empty()) core_.remove_worker(old, "registered again (restarted)");
  WorkerLink link{access_.worker_identity, who.name, &core_.grants()};
  const std::string id = core_.add_worker(
      std::make_shared<RemoteTileWorker>(request.address(), std::move(link)), true, facts_of(request));
  {
    std::lock_guard lock(mutex_);
    registered_[request.address()] = Registered{id, who.name};
    registrant_of_.erase(old);
    registrant_of_[id] = who.name;
  }
  v1::RegisterWorkerResponse response;
  response.set_worker_id(id);
  response.set_scheduler_id(core_.scheduler_id());
  response.set_heartbeat_interval_ms(static_cast<std::uint32_t>(core_.options().heartbeat_interval.count()));
  return response;
}

v1::HeartbeatResponse SchedulerFrontDoor::heartbeat(const Principal& who, const v1::HeartbeatRequest& request) {
  AccessControl::check(who, kWorkers, "Heartbeat");
  std::optional<std::string> registered_by;
  {
    std::lock_guard lock(mutex_);
    if (const auto it = registrant_of_.find(request.worker_id()); it != registrant_of_.end()) registered_by = it->second;
  }
  if (registered_by && *registered_by != who.name && !who.roles.has(Role::admin)) {
    deny(who, fmt::format("heartbeat for worker {}: '{}' registered it", utf8_prefix(request.worker_id(), 80),
                          *registered_by));
  }
  v1::HeartbeatResponse response;
  response.set_register_again(!registered_by || !core_.heartbeat(request.worker_id()));
  return response;
}

AssetUpload SchedulerFrontDoor::upload_asset(const Principal& who) {
  AccessControl::check(who, kJobSubmitters, "UploadAsset");
  return AssetUpload(core_, who.name);
}

v1::HasAssetsResponse SchedulerFrontDoor::has_assets(const Principal& who, const v1::HasAssetsRequest& request) const {
  AccessControl::check(who, kJobSubmitters, "HasAssets");
  v1::HasAssetsResponse response;
  for (const std::string& sha : request.sha256()) {
    if (!is_sha256_hex(sha)) {
      throw InputError(fmt::format("HasAssets: '{}' is not 64 lowercase hex digits", sha.substr(0, 80)));
    }
    if (!core_.assets().has(sha)) response.add_missing(sha);
  }
  return response;
}

v1::PlanSubmissionResponse SchedulerFrontDoor::plan_submission(const Principal& who,
                                                               const v1::PlanSubmissionRequest& request) const {
  AccessControl::check(who, kJobSubmitters, "PlanSubmission");
  if (!plans_.try_acquire_for(kPlanWait)) {
    throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                       "PlanSubmission: the scheduler is planning as many submissions as it reads at once "
                       "(--max-scene-checks); ask again");
  }
  struct Release {
    std::counting_semaphore<kMaxPlansAtOnce>& plans;
    ~Release() { plans.release(); }
  } release{plans_};
  return farm::plan_submission(request, core_.assets(), core_.options().limits);
}

std::filesystem::path SchedulerFrontDoor::asset_file(const Principal& who, const std::string& sha256) const {
  AccessControl::check(who, kWorkers, "GetAsset");
  if (!is_sha256_hex(sha256)) {
    throw InputError(fmt::format("GetAsset: '{}' is not 64 lowercase hex digits", sha256.substr(0, 80)));
  }
  if (!who.roles.has(Role::admin) && !core_.grants().allowed(who.name, sha256)) {
    deny(who, fmt::format("fetch asset {}: no job given to it now reads it", sha256));
  }
  if (!core_.assets().has(sha256)) throw ServiceError(grpc::StatusCode::NOT_FOUND, "no asset " + sha256);
  return core_.assets().path_of(sha256);
}

}  // namespace farm
