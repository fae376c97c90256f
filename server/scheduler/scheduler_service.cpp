#include "server/common/job_state.h"
#include "server/scheduler/scheduler_service.h"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>

#include "renderer/job/job_limits.h"
#include "renderer/util/input_error.h"
#include "renderer/util/utf8_prefix.h"
#include "server/common/hex.h"
#include "server/common/network_address.h"
#include "server/common/scene_materializer.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"

namespace farm {

namespace {

constexpr std::size_t kChunk = 1 << 20;
constexpr int kDefaultPageSize = 50;
constexpr int kMaxPageSize = 1000;
constexpr std::size_t kMaxNameFilterBytes = 256;
constexpr int kMaxLogPage = 1000;  // GetJobLog's entries a page
// A watch of a job on a shared store hears nothing for this long: the job is read (WatchJob).
constexpr auto kQuietWatchPoll = std::chrono::seconds(3);

// Runs `body`, mapping the farm's exceptions to statuses (as the worker does).
template <typename F>
grpc::Status guarded(F&& body) {
  try {
    return body();
  } catch (const std::exception&) {
    return status_of_current_exception();
  }
}

// Streams `file` in chunks of `make(offset, bytes, first)`; false when the client went away.
template <typename Chunk, typename Make>
bool stream_file(const std::filesystem::path& file, grpc::ServerWriter<Chunk>* writer,
                 grpc::ServerContext* context, Make&& make) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::string buffer(kChunk, '\0');
  std::uint64_t offset = 0;
  bool first = true;
  while (first || in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    if (n == 0 && !first) break;
    if (context->IsCancelled()) return false;
    if (!writer->Write(make(offset, std::string_view(buffer.data(), n), first))) return false;
    offset += n;
    first = false;
  }
  return true;
}

// What a registering worker says of itself, bounded: it is shown, never trusted.
WorkerFacts facts_of(const v1::RegisterWorkerRequest& r) {
  constexpr int kMaxEngines = 8;
  constexpr std::size_t kMaxText = 64;
  WorkerFacts f;
  f.threads = r.threads();  // RegisterWorker refused one outside [0, kMaxThreads]
  for (int i = 0; i < std::min(r.engines_size(), kMaxEngines); ++i) f.engines.push_back(utf8_prefix(r.engines(i), kMaxText));
  f.hostname = utf8_prefix(r.hostname(), 255);
  f.version = utf8_prefix(r.version(), kMaxText);
  return f;
}

const Roles kJobSubmitters = Role::submit | Role::admin;
const Roles kJobReaders = Role::submit | Role::read | Role::admin;
const Roles kAllJobReaders = Role::read | Role::admin;

}  // namespace

v1::Job SchedulerService::visible_job(const Principal& who, const std::string& job_id, Roles any_job,
                                      const char* rpc) const {
  std::optional<v1::Job> job = core_.get_job(job_id);
  if (!job) throw ServiceError(grpc::StatusCode::NOT_FOUND, fmt::format("no job '{}'", job_id.substr(0, 80)));
  if (!who.roles.any_of(any_job) && job->owner() != who.name) {
    deny(who, fmt::format("{} job {}: it belongs to '{}'", rpc, job_id, job->owner()));
  }
  return std::move(*job);
}

void SchedulerService::check_priority(const Principal& who, int priority, const char* what) const {
  if (priority > access_.max_priority && !who.roles.has(Role::admin)) {
    deny(who, fmt::format("{} with priority {} (above {} needs the admin role)", what, priority, access_.max_priority));
  }
}

grpc::Status SchedulerService::SubmitJob(grpc::ServerContext* context, const v1::SubmitJobRequest* request,
                                         v1::SubmitJobResponse* response) {
  return guarded([&] {
    const Principal who = access_.access.require(*context, kJobSubmitters, "SubmitJob");
    check_priority(who, request->priority(), "submit");
    *response->mutable_job() = core_.submit(request->job(), request->priority(), nullptr, who.name);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::GetJob(grpc::ServerContext* context, const v1::GetJobRequest* request,
                                      v1::Job* response) {
  return guarded([&] {
    *response = get_job(access_.access.authenticate(*context), request->job_id());
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::ListJobs(grpc::ServerContext* context, const v1::ListJobsRequest* request,
                                        v1::ListJobsResponse* response) {
  return guarded([&] {
    *response = list_jobs(access_.access.authenticate(*context), *request);
    return grpc::Status::OK;
  });
}

v1::Job SchedulerService::get_job(const Principal& who, const std::string& job_id) const {
  AccessControl::check(who, kJobReaders, "GetJob");
  return visible_job(who, job_id, kAllJobReaders, "see");
}

v1::ListJobsResponse SchedulerService::list_jobs(const Principal& who, const v1::ListJobsRequest& request) const {
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
  if (request.id_prefix().size() > 64 ||
      !is_lowercase_hex(request.id_prefix())) {
    throw InputError(fmt::format("ListJobs: id_prefix '{}' is not the start of a job id (lowercase hex)",
                                 request.id_prefix().substr(0, 64)));
  }
  filter.id_prefix = request.id_prefix();
  auto [jobs, next] = core_.store().jobs().list_jobs(filter, size, before);
  v1::ListJobsResponse response;
  for (v1::Job& job : jobs) *response.add_jobs() = std::move(job);
  if (next > 0) response.set_next_page_token(std::to_string(next));
  return response;
}

grpc::Status SchedulerService::WatchJob(grpc::ServerContext* context,
                                        const v1::WatchJobRequest* request,
                                        grpc::ServerWriter<v1::JobEvent>* writer) {
  return guarded([&] {
    const Principal who = access_.access.authenticate(*context);
    AccessControl::check(who, kJobReaders, "WatchJob");
    // Subscribe before the snapshot, so no event falls between them (a caller the snapshot then
    // refuses is unsubscribed on the way out).
    const std::shared_ptr<JobEventQueue> queue = core_.watch(request->job_id());
    struct Unwatch {
      SchedulerCore& core;
      const std::string& id;
      const std::shared_ptr<JobEventQueue>& queue;
      ~Unwatch() { core.unwatch(id, queue); }
    } unwatch{core_, request->job_id(), queue};

    const v1::Job job = watchable_job(who, request->job_id());
    v1::JobEvent event;
    *event.mutable_job() = job;
    event.mutable_snapshot();
    if (!writer->Write(event)) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
    if (is_final(job.state())) return grpc::Status::OK;
    v1::JobState last = job.state();
    auto heard = std::chrono::steady_clock::now();
    while (true) {
      // Polls for a client that went away, so a watch never outlives its caller.
      if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
      if (!queue->pop(event, std::chrono::milliseconds(200))) {
        // On a store other schedulers share, their events come through the relay, which may miss
        // some (its link down): after a quiet while the job is read here, so a state change,
        // its end above all, reaches the watcher all the same.
        if (!core_.store().is_shared() || std::chrono::steady_clock::now() - heard < kQuietWatchPoll) continue;
        heard = std::chrono::steady_clock::now();
        std::optional<v1::Job> now;
        try {
          now = core_.get_job(request->job_id());
        } catch (const StoreUnavailable&) {
          continue;  // the store away: the watch waits for it, as the job does
        }
        if (!now || now->state() == last) continue;
        event.Clear();
        *event.mutable_job() = *now;
        event.mutable_state_changed()->set_from(last);
        event.mutable_state_changed()->set_to(now->state());
      }
      heard = std::chrono::steady_clock::now();
      if (event.has_state_changed()) last = event.job().state();
      if (!writer->Write(event)) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
      if (event.has_state_changed() && is_final(event.job().state())) return grpc::Status::OK;
    }
  });
}

v1::Job SchedulerService::watchable_job(const Principal& who, const std::string& job_id) const {
  AccessControl::check(who, kJobReaders, "WatchJob");
  return visible_job(who, job_id, kAllJobReaders, "watch");
}

grpc::Status SchedulerService::CancelJob(grpc::ServerContext* context, const v1::CancelJobRequest* request,
                                         v1::CancelJobResponse* response) {
  return guarded([&] {
    *response->mutable_job() = cancel_job(access_.access.authenticate(*context), request->job_id());
    return grpc::Status::OK;
  });
}

v1::Job SchedulerService::cancel_job(const Principal& who, const std::string& job_id) {
  AccessControl::check(who, kJobSubmitters, "CancelJob");
  visible_job(who, job_id, Role::admin, "cancel");
  return core_.cancel(job_id, who.name);
}

grpc::Status SchedulerService::PauseJob(grpc::ServerContext* context, const v1::PauseJobRequest* request,
                                        v1::PauseJobResponse* response) {
  return guarded([&] {
    *response->mutable_job() = pause_job(access_.access.authenticate(*context), request->job_id(), request->paused());
    return grpc::Status::OK;
  });
}

v1::Job SchedulerService::pause_job(const Principal& who, const std::string& job_id, bool paused) {
  AccessControl::check(who, kJobSubmitters, "PauseJob");
  visible_job(who, job_id, Role::admin, paused ? "pause" : "resume");
  return core_.pause(job_id, paused, who.name);
}

grpc::Status SchedulerService::SetPriority(grpc::ServerContext* context, const v1::SetPriorityRequest* request,
                                           v1::SetPriorityResponse* response) {
  return guarded([&] {
    *response->mutable_job() = set_priority(access_.access.authenticate(*context), request->job_id(), request->priority());
    return grpc::Status::OK;
  });
}

v1::Job SchedulerService::set_priority(const Principal& who, const std::string& job_id, int priority) {
  AccessControl::check(who, kJobSubmitters, "SetPriority");
  visible_job(who, job_id, Role::admin, "re-prioritise");
  check_priority(who, priority, "re-prioritise");
  return core_.set_priority(job_id, priority, who.name);
}

grpc::Status SchedulerService::RetryJob(grpc::ServerContext* context, const v1::RetryJobRequest* request,
                                        v1::RetryJobResponse* response) {
  return guarded([&] {
    *response = retry_job(access_.access.authenticate(*context), request->job_id());
    return grpc::Status::OK;
  });
}

v1::RetryJobResponse SchedulerService::retry_job(const Principal& who, const std::string& job_id) {
  AccessControl::check(who, kJobSubmitters, "RetryJob");
  visible_job(who, job_id, Role::admin, "retry");
  RetriedJob r = core_.retry(job_id, who.name);
  v1::RetryJobResponse response;
  *response.mutable_job() = std::move(r.job);
  response.set_units_queued(r.units_queued);
  return response;
}

grpc::Status SchedulerService::DeleteJob(grpc::ServerContext* context, const v1::DeleteJobRequest* request,
                                         v1::DeleteJobResponse* response) {
  return guarded([&] {
    *response = delete_job(access_.access.authenticate(*context), request->job_id());
    return grpc::Status::OK;
  });
}

v1::DeleteJobResponse SchedulerService::delete_job(const Principal& who, const std::string& job_id) {
  AccessControl::check(who, kJobSubmitters, "DeleteJob");
  visible_job(who, job_id, Role::admin, "delete");
  v1::DeleteJobResponse response;
  response.set_bytes_freed(core_.remove(job_id));
  response.set_job_id(job_id);
  return response;
}

grpc::Status SchedulerService::GetJobLog(grpc::ServerContext* context, const v1::GetJobLogRequest* request,
                                         v1::GetJobLogResponse* response) {
  return guarded([&] {
    *response = job_log(access_.access.authenticate(*context), *request);
    return grpc::Status::OK;
  });
}

v1::GetJobLogResponse SchedulerService::job_log(const Principal& who, const v1::GetJobLogRequest& request) const {
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

grpc::Status SchedulerService::ListWorkers(grpc::ServerContext* context, const v1::ListWorkersRequest*,
                                           v1::ListWorkersResponse* response) {
  return guarded([&] {
    *response = list_workers(access_.access.authenticate(*context));
    return grpc::Status::OK;
  });
}

v1::ListWorkersResponse SchedulerService::list_workers(const Principal& who) const {
  AccessControl::check(who, kAllJobReaders, "ListWorkers");
  v1::ListWorkersResponse response;
  for (v1::WorkerInfo& w : core_.worker_infos()) *response.add_workers() = std::move(w);
  return response;
}

std::filesystem::path SchedulerService::result_file(const Principal& who, const v1::GetResultRequest& request) const {
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

grpc::Status SchedulerService::GetResult(grpc::ServerContext* context,
                                         const v1::GetResultRequest* request,
                                         grpc::ServerWriter<v1::FileChunk>* writer) {
  return guarded([&] {
    const std::filesystem::path file = result_file(access_.access.authenticate(*context), *request);
    const std::string sha = sha256_file_hex(file);
    const std::uint64_t size = std::filesystem::file_size(file);
    const bool complete = stream_file(file, writer, context,
                                      [&](std::uint64_t offset, std::string_view bytes, bool first) {
      v1::FileChunk chunk;
      if (first) {
        chunk.set_file_name(file.filename().string());
        chunk.set_total_size(size);
        chunk.set_sha256(sha);
      }
      chunk.set_offset(offset);
      chunk.set_data(std::string(bytes));
      return chunk;
    });
    return complete ? grpc::Status::OK : grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
  });
}

grpc::Status SchedulerService::UploadAsset(grpc::ServerContext* context,
                                           grpc::ServerReader<v1::UploadAssetRequest>* reader,
                                           v1::UploadAssetResponse* response) {
  return guarded([&] {
    const Principal who = access_.access.require(*context, kJobSubmitters, "UploadAsset");
    StreamWatchdog::Watch watch = uploads_.watch(*context);
    v1::UploadAssetRequest part;
    if (!reader->Read(&part) || !part.has_header()) {
      throw InputError("UploadAsset: the first message must be an AssetHeader");
    }
    const v1::AssetHeader header = part.header();
    if (!is_sha256_hex(header.sha256())) {
      throw InputError(fmt::format("UploadAsset: sha256 '{}' is not 64 lowercase hex digits",
                                   header.sha256().substr(0, 80)));
    }
    if (const std::uint64_t limit = core_.options().limits.max_asset_bytes; header.size() > limit) {
      throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                         fmt::format("asset of {} bytes: at most {} (--max-asset-bytes)", header.size(), limit));
    }
    response->set_sha256(header.sha256());
    response->set_size(header.size());
    if (core_.assets().has(header.sha256())) {
      while (reader->Read(&part)) watch.touch();
      response->set_already_present(true);
      return grpc::Status::OK;
    }
    const AssetQuota::Reservation reserved = core_.asset_quota().reserve(header.size(), who.name);
    AssetStore::Writer writer = core_.assets().begin(header.sha256(), header.size());
    while (reader->Read(&part)) {
      watch.touch();
      if (!part.has_data() && part.has_header()) throw InputError("UploadAsset: a second AssetHeader");
      if (writer.bytes_written() + part.data().size() > header.size()) {
        throw InputError(fmt::format("UploadAsset: more than the {} bytes the header announced",
                                     header.size()));
      }
      writer.append(part.data());
    }
    if (watch.timed_out()) {
      throw ServiceError(grpc::StatusCode::DEADLINE_EXCEEDED,
                         fmt::format("UploadAsset: nothing arrived for {} ms; the upload was ended and its quota freed",
                                     uploads_.idle_limit().count()));
    }
    writer.commit();  // InputError when the bytes do not hash to the header's sha256
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::HasAssets(grpc::ServerContext* context, const v1::HasAssetsRequest* request,
                                         v1::HasAssetsResponse* response) {
  return guarded([&] {
    access_.access.require(*context, kJobSubmitters, "HasAssets");
    for (const std::string& sha : request->sha256()) {
      if (!is_sha256_hex(sha)) {
        throw InputError(fmt::format("HasAssets: '{}' is not 64 lowercase hex digits", sha.substr(0, 80)));
      }
      if (!core_.assets().has(sha)) response->add_missing(sha);
    }
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::GetAsset(grpc::ServerContext* context,
                                        const v1::GetAssetRequest* request,
                                        grpc::ServerWriter<v1::AssetChunk>* writer) {
  return guarded([&] {
    const Principal who = access_.access.require(*context, Role::worker | Role::admin, "GetAsset");
    if (!is_sha256_hex(request->sha256())) {
      throw InputError(fmt::format("GetAsset: '{}' is not 64 lowercase hex digits",
                                   request->sha256().substr(0, 80)));
    }
    if (!who.roles.has(Role::admin) && !core_.grants().allowed(who.name, request->sha256())) {
      deny(who, fmt::format("fetch asset {}: no job given to it now reads it", request->sha256()));
    }
    if (!core_.assets().has(request->sha256())) {
      return grpc::Status(grpc::StatusCode::NOT_FOUND, "no asset " + request->sha256());
    }
    const std::filesystem::path file = core_.assets().path_of(request->sha256());
    const std::uint64_t size = std::filesystem::file_size(file);
    const bool complete = stream_file(file, writer, context,
                                      [&](std::uint64_t offset, std::string_view bytes, bool) {
      v1::AssetChunk chunk;
      chunk.set_total_size(size);
      chunk.set_offset(offset);
      chunk.set_data(std::string(bytes));
      return chunk;
    });
    return complete ? grpc::Status::OK : grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
  });
}

grpc::Status SchedulerService::RegisterWorker(grpc::ServerContext* context,
                                              const v1::RegisterWorkerRequest* request,
                                              v1::RegisterWorkerResponse* response) {
  return guarded([&] {
    const Principal who = access_.access.require(*context, Role::worker | Role::admin, "RegisterWorker");
    if (const std::string problem = worker_address_problem(request->address()); !problem.empty()) {
      throw InputError(fmt::format("RegisterWorker: address '{}': {}", utf8_prefix(request->address(), 80), problem));
    }
    if (request->threads() < 0 || request->threads() > kMaxThreads) {
      throw InputError(fmt::format("RegisterWorker: threads {}: give 0 (not known) to {}", request->threads(), kMaxThreads));
    }
    std::string old;
    {
      std::lock_guard lock(mutex_);
      if (auto it = registered_.find(request->address()); it != registered_.end()) {
        if (it->second.principal != who.name && !who.roles.has(Role::admin)) {
          deny(who, fmt::format("register at {}: '{}' registered a worker there", request->address(),
                                it->second.principal));
        }
        old = it->second.worker_id;
      }
    }
    // A worker registering again at the same address restarted: its old calls are dead.
    if (!old.empty()) core_.remove_worker(old, "registered again (restarted)");
    WorkerLink link{access_.worker_identity, who.name, &core_.grants()};
    const std::string id = core_.add_worker(
        std::make_shared<RemoteTileWorker>(request->address(), std::move(link)), true, facts_of(*request));
    {
      std::lock_guard lock(mutex_);
      registered_[request->address()] = Registered{id, who.name};
      registrant_of_.erase(old);
      registrant_of_[id] = who.name;
    }
    response->set_worker_id(id);
    response->set_scheduler_id(core_.scheduler_id());
    response->set_heartbeat_interval_ms(
        static_cast<std::uint32_t>(core_.options().heartbeat_interval.count()));
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::Heartbeat(grpc::ServerContext* context, const v1::HeartbeatRequest* request,
                                         v1::HeartbeatResponse* response) {
  return guarded([&] {
    const Principal who = access_.access.require(*context, Role::worker | Role::admin, "Heartbeat");
    // Only for a worker this caller registered: a worker token cannot keep another's worker alive.
    std::optional<std::string> registered_by;
    {
      std::lock_guard lock(mutex_);
      if (const auto it = registrant_of_.find(request->worker_id()); it != registrant_of_.end()) registered_by = it->second;
    }
    if (registered_by && *registered_by != who.name && !who.roles.has(Role::admin)) {
      deny(who, fmt::format("heartbeat for worker {}: '{}' registered it", utf8_prefix(request->worker_id(), 80),
                            *registered_by));
    }
    response->set_register_again(!registered_by || !core_.heartbeat(request->worker_id()));
    return grpc::Status::OK;
  });
}

}  // namespace farm
