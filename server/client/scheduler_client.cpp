#include "server/client/scheduler_client.h"

#include <fmt/format.h>
#include <fcntl.h>
#include <grpcpp/grpcpp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

#include <fstream>
#include <stdexcept>

#include "renderer/util/atomic_file.h"
#include "renderer/util/input_error.h"
#include "server/common/hex.h"
#include "server/common/plain_file_name.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kChunkBytes = 1 << 20;  // well under gRPC's 4 MiB message limit

}  // namespace

template <typename Response, typename Request, typename Method>
Response SchedulerClient::call(Method method, const Request& request, const char* what) {
  Response response;
  grpc::ClientContext context;
  const grpc::Status status = (stub_.get()->*method)(&context, request, &response);
  if (!status.ok()) throw_for_status(status, what, address_);
  return response;
}

void throw_for_status(const grpc::Status& status, const std::string& what, const std::string& address) {
  switch (status.error_code()) {
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::NOT_FOUND:
    case grpc::StatusCode::FAILED_PRECONDITION:
    case grpc::StatusCode::ALREADY_EXISTS:
    case grpc::StatusCode::OUT_OF_RANGE:
    case grpc::StatusCode::RESOURCE_EXHAUSTED:  // a job over a scheduler's limit: the job is too big
      throw InputError(status.error_message());
    case grpc::StatusCode::UNAVAILABLE:
      throw ServiceError(grpc::StatusCode::UNAVAILABLE, fmt::format(
          "{}: cannot reach the scheduler at {} ({}); is `farm scheduler` running there? "
          "(--scheduler ADDR or FARM_SCHEDULER say where)",
          what, address, status.error_message()));
    case grpc::StatusCode::UNAUTHENTICATED:
    case grpc::StatusCode::PERMISSION_DENIED:
      throw ServiceError(status.error_code(),
                         fmt::format("{}: the scheduler at {} refused ({}): {}", what, address,
                                     status_code_name(status.error_code()), status.error_message()));
    default:
      throw std::runtime_error(fmt::format("{}: the scheduler at {} answered {}: {}", what, address,
                                           static_cast<int>(status.error_code()), status.error_message()));
  }
}

SchedulerClient::SchedulerClient(SchedulerConnection connection)
    : address_(std::move(connection.address)),
      stub_(v1::Scheduler::NewStub(open_channel(address_, connection.identity))) {}

std::size_t SchedulerClient::upload_missing(const JobSubmission& submission) {
  v1::HasAssetsRequest ask;
  for (const auto& [sha, file] : submission.files) ask.add_sha256(sha);
  const auto missing = call<v1::HasAssetsResponse>(&v1::Scheduler::Stub::HasAssets, ask, "HasAssets");
  for (const std::string& sha : missing.missing()) {
    const auto it = submission.files.find(sha);
    if (it == submission.files.end()) continue;
    // The file was confined and hashed when the submission was made; opened again here without
    // following a link or waiting on a FIFO, in case it was swapped since (the scheduler checks
    // the bytes against the hash).
    const int fd = ::open(it->second.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    struct stat st {};
    if (fd < 0 || ::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
      if (fd >= 0) ::close(fd);
      throw InputError(fmt::format("{}: cannot read the asset (no longer a regular file)", it->second.string()));
    }
    struct Close {
      int fd;
      ~Close() { ::close(fd); }
    } close_fd{fd};
    grpc::ClientContext context;
    v1::UploadAssetResponse response;
    auto writer = stub_->UploadAsset(&context, &response);
    v1::UploadAssetRequest header;
    header.mutable_header()->set_sha256(sha);
    header.mutable_header()->set_size(static_cast<std::uint64_t>(st.st_size));
    bool open = writer->Write(header);
    std::string buffer(kChunkBytes, '\0');
    while (open) {
      const ssize_t got = ::read(fd, buffer.data(), buffer.size());
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) throw InputError(fmt::format("{}: cannot read the asset", it->second.string()));
      if (got == 0) break;
      v1::UploadAssetRequest chunk;
      chunk.set_data(buffer.data(), static_cast<std::size_t>(got));
      open = writer->Write(chunk);
    }
    writer->WritesDone();
    const grpc::Status status = writer->Finish();
    if (!status.ok()) throw_for_status(status, fmt::format("uploading {}", it->second.string()), address_);
  }
  return static_cast<std::size_t>(missing.missing_size());
}

v1::Job SchedulerClient::submit(const JobSubmission& submission, int priority) {
  v1::SubmitJobRequest request;
  request.set_priority(priority);
  return submit(submission, std::move(request));
}

v1::Job SchedulerClient::submit(const JobSubmission& submission, v1::SubmitJobRequest request) {
  *request.mutable_job() = submission.spec;
  return call<v1::SubmitJobResponse>(&v1::Scheduler::Stub::SubmitJob, request, "SubmitJob").job();
}

v1::Job SchedulerClient::get(const std::string& job_id) {
  v1::GetJobRequest request;
  request.set_job_id(job_id);
  return call<v1::Job>(&v1::Scheduler::Stub::GetJob, request, "GetJob");
}

std::vector<v1::Job> SchedulerClient::list(const JobListing& listing, bool* more) {
  constexpr std::size_t kPage = 1000;  // the scheduler's largest page
  std::vector<v1::Job> jobs;
  std::string token;
  if (more) *more = false;
  do {
    v1::ListJobsRequest request;
    for (v1::JobState s : listing.states) request.add_states(s);
    request.set_name(listing.name);
    request.set_id_prefix(listing.id_prefix);
    request.set_page_token(token);
    // One more than the limit, so that `more` can be told.
    const std::size_t wanted = listing.limit == 0 ? kPage : listing.limit + 1 - jobs.size();
    request.set_page_size(static_cast<int>(std::min(wanted, kPage)));
    const auto response = call<v1::ListJobsResponse>(&v1::Scheduler::Stub::ListJobs, request, "ListJobs");
    jobs.insert(jobs.end(), response.jobs().begin(), response.jobs().end());
    token = response.next_page_token();
  } while (!token.empty() && (listing.limit == 0 || jobs.size() <= listing.limit));
  if (listing.limit > 0 && jobs.size() > listing.limit) {
    if (more) *more = true;
    jobs.resize(listing.limit);
  }
  return jobs;
}

std::string SchedulerClient::resolve_job_id(const std::string& id_or_prefix) {
  // Not an id's start at all: asked for as it is, and the scheduler says what is wrong with it.
  if (id_or_prefix.empty() || !is_lowercase_hex(id_or_prefix)) {
    return id_or_prefix;
  }
  bool more = false;
  const std::vector<v1::Job> matches = list({.id_prefix = id_or_prefix, .limit = 3}, &more);
  if (matches.size() == 1) return matches.front().job_id();
  if (matches.empty()) {
    throw ServiceError(grpc::StatusCode::NOT_FOUND,
                       fmt::format("no job on {} whose id starts with '{}'", address_, id_or_prefix));
  }
  std::string named;
  for (const v1::Job& j : matches) named += fmt::format("{}{} '{}'", named.empty() ? "" : ", ", j.job_id(), j.name());
  throw InputError(fmt::format("job id '{}' is ambiguous on {}: {}{}; give more of it", id_or_prefix, address_, named,
                               more ? " and more" : ""));
}

std::vector<std::string> SchedulerClient::resolve_job_ids(const std::vector<std::string>& ids_or_prefixes) {
  std::vector<std::string> ids;
  for (const std::string& id : ids_or_prefixes) ids.push_back(resolve_job_id(id));
  return ids;
}

v1::Job SchedulerClient::watch(const std::string& job_id,
                               const std::function<void(const v1::JobEvent&)>& on_event) {
  v1::WatchJobRequest request;
  request.set_job_id(job_id);
  grpc::ClientContext context;
  auto reader = stub_->WatchJob(&context, request);
  v1::JobEvent event;
  v1::Job last;
  while (reader->Read(&event)) {
    last = event.job();
    if (on_event) on_event(event);
    if (is_final(last.state())) break;
  }
  if (is_final(last.state())) {
    context.TryCancel();  // the stream ends after the final event; do not wait for it
    return last;
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) throw_for_status(status, "WatchJob", address_);
  // The stream ended without a final state (the scheduler restarted): ask once more.
  return get(job_id);
}

v1::Job SchedulerClient::cancel(const std::string& job_id) {
  v1::CancelJobRequest request;
  request.set_job_id(job_id);
  return call<v1::CancelJobResponse>(&v1::Scheduler::Stub::CancelJob, request, "CancelJob").job();
}

v1::Job SchedulerClient::pause(const std::string& job_id, bool paused) {
  v1::PauseJobRequest request;
  request.set_job_id(job_id);
  request.set_paused(paused);
  return call<v1::PauseJobResponse>(&v1::Scheduler::Stub::PauseJob, request, "PauseJob").job();
}

v1::Job SchedulerClient::set_priority(const std::string& job_id, int priority) {
  v1::SetPriorityRequest request;
  request.set_job_id(job_id);
  request.set_priority(priority);
  return call<v1::SetPriorityResponse>(&v1::Scheduler::Stub::SetPriority, request, "SetPriority").job();
}

v1::Job SchedulerClient::set_limits(const std::string& job_id, std::optional<std::uint32_t> max_workers,
                                    std::optional<std::uint32_t> max_units_in_flight) {
  v1::SetJobLimitsRequest request;
  request.set_job_id(job_id);
  if (max_workers) request.set_max_workers(*max_workers);
  if (max_units_in_flight) request.set_max_units_in_flight(*max_units_in_flight);
  return call<v1::SetJobLimitsResponse>(&v1::Scheduler::Stub::SetJobLimits, request, "SetJobLimits").job();
}

v1::Job SchedulerClient::add_dependencies(const std::string& job_id, const std::vector<std::string>& after,
                                          const std::vector<std::string>& after_any) {
  v1::AddDependenciesRequest request;
  request.set_job_id(job_id);
  for (const std::string& id : after) request.add_after(id);
  for (const std::string& id : after_any) request.add_after_any(id);
  return call<v1::AddDependenciesResponse>(&v1::Scheduler::Stub::AddDependencies, request, "AddDependencies").job();
}

v1::RetryJobResponse SchedulerClient::retry(const std::string& job_id) {
  v1::RetryJobRequest request;
  request.set_job_id(job_id);
  return call<v1::RetryJobResponse>(&v1::Scheduler::Stub::RetryJob, request, "RetryJob");
}

v1::DeleteJobResponse SchedulerClient::remove(const std::string& job_id) {
  v1::DeleteJobRequest request;
  request.set_job_id(job_id);
  return call<v1::DeleteJobResponse>(&v1::Scheduler::Stub::DeleteJob, request, "DeleteJob");
}

std::vector<v1::JobLogEntry> SchedulerClient::log(const std::string& job_id) {
  std::vector<v1::JobLogEntry> entries;
  v1::GetJobLogRequest request;
  request.set_job_id(job_id);
  for (;;) {
    v1::GetJobLogResponse page = call<v1::GetJobLogResponse>(&v1::Scheduler::Stub::GetJobLog, request, "GetJobLog");
    // A page that does not move past where it began would loop for ever: the reply is checked.
    for (v1::JobLogEntry& e : *page.mutable_entries()) {
      if (e.number() <= request.after()) throw std::runtime_error("GetJobLog: the scheduler sent entries out of order");
      request.set_after(e.number());
      entries.push_back(std::move(e));
    }
    if (!page.more() || page.entries().empty()) return entries;
  }
}

std::vector<v1::WorkerInfo> SchedulerClient::workers() {
  v1::ListWorkersResponse response =
      call<v1::ListWorkersResponse>(&v1::Scheduler::Stub::ListWorkers, v1::ListWorkersRequest(), "ListWorkers");
  return {std::make_move_iterator(response.mutable_workers()->begin()),
          std::make_move_iterator(response.mutable_workers()->end())};
}

fs::path SchedulerClient::fetch(const std::string& job_id, v1::ResultKind kind, const Destination& where,
                               std::optional<int> frame) {
  v1::GetResultRequest request;
  request.set_job_id(job_id);
  request.set_kind(kind);
  if (frame) request.set_frame(*frame);
  grpc::ClientContext context;
  auto reader = stub_->GetResult(&context, request);
  v1::FileChunk chunk;
  if (!reader->Read(&chunk)) {
    const grpc::Status status = reader->Finish();
    if (!status.ok()) throw_for_status(status, "GetResult", address_);
    throw std::runtime_error("GetResult: the scheduler sent no data");
  }
  // Only a plain file name from the scheduler is passed on, never a path ("..", "a/b").
  const fs::path file = where(plain_file_name(chunk.file_name(), ""));
  const std::string expected_sha = chunk.sha256();
  const std::uint64_t total = chunk.total_size();
  // Written whole or not at all: a call that breaks off, or bytes that arrive damaged, leave
  // nothing where the result should be.
  write_file_atomically(file, [&](const fs::path& temp) {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(fmt::format("{}: cannot write", temp.string()));
    Sha256 hash;
    std::uint64_t written = 0;
    do {
      if (chunk.offset() != written) {
        throw std::runtime_error(
            fmt::format("GetResult: chunk at offset {} where {} was expected", chunk.offset(), written));
      }
      out.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
      hash.update(chunk.data());
      written += chunk.data().size();
    } while (reader->Read(&chunk));
    const grpc::Status status = reader->Finish();
    if (!status.ok()) throw_for_status(status, "GetResult", address_);
    out.close();
    if (!out) throw InputError(fmt::format("{}: cannot write", temp.string()));
    const std::string got = hash.finish_hex();
    if ((total != 0 && written != total) || (!expected_sha.empty() && got != expected_sha)) {
      throw std::runtime_error(fmt::format("GetResult: {} arrived damaged ({} of {} bytes, sha256 {})",
                                           file.string(), written, total, got));
    }
  });
  return file;
}

}  // namespace farm
