#include "server/scheduler/scheduler_service.h"

#include <fmt/format.h>

#include <fstream>
#include <utility>

#include "renderer/util/input_error.h"
#include "server/common/job_state.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"

namespace farm {

namespace {

constexpr std::size_t kChunk = 1 << 20;
// How long WatchJob waits for an event before it looks again whether its client went away.
constexpr auto kWatchPoll = std::chrono::milliseconds(200);

// Runs `body`, mapping the farm's exceptions to statuses (as the worker does).
template <typename F>
grpc::Status guarded(F&& body) {
  try {
    return body();
  } catch (const std::exception&) {
    return status_of_current_exception();
  }
}

const grpc::Status kClientWentAway(grpc::StatusCode::CANCELLED, "client went away");

// A file to send, opened once: its size, its hash and its bytes all come from this one open file.
// A result may be replaced while it is sent (a progressive preview renamed over by the next
// pass's): opened once, the old one is sent whole and its sha256 is of the bytes sent. Opened
// three times (hash, size, bytes), a fetch could get one version's hash with the other's bytes
// (FarmPassesTest: "sha256 mismatch").
struct FileToSend {
  std::filesystem::path file;
  std::ifstream in;
  std::uint64_t size = 0;

  explicit FileToSend(std::filesystem::path path) : file(std::move(path)), in(file, std::ios::binary) {
    if (!in) throw std::runtime_error("cannot read " + file.string());
    in.seekg(0, std::ios::end);
    size = static_cast<std::uint64_t>(in.tellg());
    in.seekg(0);
  }
  // Reads it all, then starts it again from its first byte.
  std::string sha256() {
    std::string sha = sha256_stream_hex(in, file.string());
    in.clear();
    in.seekg(0);
    return sha;
  }
};

// Streams `in` in chunks of `make(offset, bytes, first)`; false when the client went away.
template <typename Chunk, typename Make>
bool stream_file(std::ifstream& in, grpc::ServerWriter<Chunk>* writer, grpc::ServerContext* context, Make&& make) {
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

}  // namespace

grpc::Status SchedulerService::SubmitJob(grpc::ServerContext* context, const v1::SubmitJobRequest* request,
                                         v1::SubmitJobResponse* response) {
  return guarded([&] {
    *response->mutable_job() = front_door_.submit(caller(*context), *request);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::GetJob(grpc::ServerContext* context, const v1::GetJobRequest* request,
                                      v1::Job* response) {
  return guarded([&] {
    *response = front_door_.get_job(caller(*context), request->job_id());
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::ListJobs(grpc::ServerContext* context, const v1::ListJobsRequest* request,
                                        v1::ListJobsResponse* response) {
  return guarded([&] {
    *response = front_door_.list_jobs(caller(*context), *request);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::WatchJob(grpc::ServerContext* context,
                                        const v1::WatchJobRequest* request,
                                        grpc::ServerWriter<v1::JobEvent>* writer) {
  return guarded([&] {
    const std::unique_ptr<JobWatch> watch = front_door_.watch_job(caller(*context), request->job_id());
    v1::JobEvent event;
    *event.mutable_job() = watch->snapshot();
    event.mutable_snapshot();
    if (!writer->Write(event)) return kClientWentAway;
    if (is_final(watch->snapshot().state())) return grpc::Status::OK;
    while (true) {
      // Polls for a client that went away, so a watch never outlives its caller.
      if (context->IsCancelled()) return kClientWentAway;
      if (!watch->next(event, kWatchPoll)) continue;
      if (!writer->Write(event)) return kClientWentAway;
      if (event.has_state_changed() && is_final(event.job().state())) return grpc::Status::OK;
    }
  });
}

grpc::Status SchedulerService::CancelJob(grpc::ServerContext* context, const v1::CancelJobRequest* request,
                                         v1::CancelJobResponse* response) {
  return guarded([&] {
    *response->mutable_job() = front_door_.cancel_job(caller(*context), request->job_id());
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::PauseJob(grpc::ServerContext* context, const v1::PauseJobRequest* request,
                                        v1::PauseJobResponse* response) {
  return guarded([&] {
    *response->mutable_job() = front_door_.pause_job(caller(*context), request->job_id(), request->paused());
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::SetPriority(grpc::ServerContext* context, const v1::SetPriorityRequest* request,
                                           v1::SetPriorityResponse* response) {
  return guarded([&] {
    *response->mutable_job() = front_door_.set_priority(caller(*context), request->job_id(), request->priority());
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::SetJobLimits(grpc::ServerContext* context, const v1::SetJobLimitsRequest* request,
                                            v1::SetJobLimitsResponse* response) {
  return guarded([&] {
    *response->mutable_job() = front_door_.set_job_limits(caller(*context), *request);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::AddDependencies(grpc::ServerContext* context, const v1::AddDependenciesRequest* request,
                                               v1::AddDependenciesResponse* response) {
  return guarded([&] {
    *response->mutable_job() = front_door_.add_dependencies(caller(*context), *request);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::RetryJob(grpc::ServerContext* context, const v1::RetryJobRequest* request,
                                        v1::RetryJobResponse* response) {
  return guarded([&] {
    *response = front_door_.retry_job(caller(*context), request->job_id());
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::DeleteJob(grpc::ServerContext* context, const v1::DeleteJobRequest* request,
                                         v1::DeleteJobResponse* response) {
  return guarded([&] {
    *response = front_door_.delete_job(caller(*context), request->job_id());
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::GetJobLog(grpc::ServerContext* context, const v1::GetJobLogRequest* request,
                                         v1::GetJobLogResponse* response) {
  return guarded([&] {
    *response = front_door_.job_log(caller(*context), *request);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::ListWorkers(grpc::ServerContext* context, const v1::ListWorkersRequest*,
                                           v1::ListWorkersResponse* response) {
  return guarded([&] {
    *response = front_door_.list_workers(caller(*context));
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::GetResult(grpc::ServerContext* context,
                                         const v1::GetResultRequest* request,
                                         grpc::ServerWriter<v1::FileChunk>* writer) {
  return guarded([&] {
    const std::filesystem::path file = front_door_.result_file(caller(*context), *request);
    FileToSend open(file);
    const std::string sha = open.sha256();
    const std::uint64_t size = open.size;
    const bool complete = stream_file(open.in, writer, context,
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
    return complete ? grpc::Status::OK : kClientWentAway;
  });
}

grpc::Status SchedulerService::UploadAsset(grpc::ServerContext* context,
                                           grpc::ServerReader<v1::UploadAssetRequest>* reader,
                                           v1::UploadAssetResponse* response) {
  return guarded([&] {
    AssetUpload upload = front_door_.upload_asset(caller(*context));
    StreamWatchdog::Watch watch = uploads_.watch(*context);
    v1::UploadAssetRequest part;
    if (!reader->Read(&part) || !part.has_header()) {
      throw InputError("UploadAsset: the first message must be an AssetHeader");
    }
    const v1::AssetHeader header = part.header();
    const bool write = upload.begin(header);
    response->set_sha256(header.sha256());
    response->set_size(header.size());
    if (!write) {
      while (reader->Read(&part)) watch.touch();
      response->set_already_present(true);
      return grpc::Status::OK;
    }
    while (reader->Read(&part)) {
      watch.touch();
      if (!part.has_data() && part.has_header()) throw InputError("UploadAsset: a second AssetHeader");
      upload.append(part.data());
    }
    if (watch.timed_out()) {
      throw ServiceError(grpc::StatusCode::DEADLINE_EXCEEDED,
                         fmt::format("UploadAsset: nothing arrived for {} ms; the upload was ended and its quota freed",
                                     uploads_.idle_limit().count()));
    }
    upload.commit();
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::HasAssets(grpc::ServerContext* context, const v1::HasAssetsRequest* request,
                                         v1::HasAssetsResponse* response) {
  return guarded([&] {
    *response = front_door_.has_assets(caller(*context), *request);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::PlanSubmission(grpc::ServerContext* context, const v1::PlanSubmissionRequest* request,
                                              v1::PlanSubmissionResponse* response) {
  return guarded([&] {
    *response = front_door_.plan_submission(caller(*context), *request);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::GetAsset(grpc::ServerContext* context,
                                        const v1::GetAssetRequest* request,
                                        grpc::ServerWriter<v1::AssetChunk>* writer) {
  return guarded([&] {
    const std::filesystem::path file = front_door_.asset_file(caller(*context), request->sha256());
    FileToSend open(file);
    const std::uint64_t size = open.size;
    const bool complete = stream_file(open.in, writer, context,
                                      [&](std::uint64_t offset, std::string_view bytes, bool) {
      v1::AssetChunk chunk;
      chunk.set_total_size(size);
      chunk.set_offset(offset);
      chunk.set_data(std::string(bytes));
      return chunk;
    });
    return complete ? grpc::Status::OK : kClientWentAway;
  });
}

grpc::Status SchedulerService::RegisterWorker(grpc::ServerContext* context,
                                              const v1::RegisterWorkerRequest* request,
                                              v1::RegisterWorkerResponse* response) {
  return guarded([&] {
    *response = front_door_.register_worker(caller(*context), *request);
    return grpc::Status::OK;
  });
}

grpc::Status SchedulerService::Heartbeat(grpc::ServerContext* context, const v1::HeartbeatRequest* request,
                                         v1::HeartbeatResponse* response) {
  return guarded([&] {
    *response = front_door_.heartbeat(caller(*context), *request);
    return grpc::Status::OK;
  });
}

}  // namespace farm
