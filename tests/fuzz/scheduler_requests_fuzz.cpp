// The scheduler's request handlers (server/scheduler/scheduler_service.cpp over the front door,
// front_door.cpp, over SchedulerCore): one real SchedulerService with a data dir in the scratch
// folder, served in process, called through the generated stub as a client on the network would
// call it.
//
// An input is one call: its first byte picks the RPC (mod 12, in proto/farm.proto's order, then
// PlanSubmission, added later, as 11), and
// the rest is the serialized request. UploadAsset, a client stream, takes the rest as messages
// each prefixed by its length (2 bytes, little endian). A job_id of "@" stands for the job the
// last successful SubmitJob made, since the fuzzer cannot guess the scheduler's ids.
//
// The example jobs' assets (jobs/assets) are uploaded once at start, so that a SubmitJob seed
// built from jobs/*.json (make_seeds.py) gets past the asset check into parse_job and the scene
// build. Each job submitted is cancelled at once: the core stays small however long the run.
//
// Property: every call returns (a status, whatever it is); a crash, a hang (libFuzzer's
// -timeout) or unbounded growth (-rss_limit_mb) is a finding.
#include <google/protobuf/stubs/logging.h>
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/log.h"
#include "server/common/sha256.h"
#include "server/scheduler/scheduler_core.h"
#include "server/scheduler/scheduler_service.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

namespace v1 = farm::v1;
using std::chrono::milliseconds;

std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

farm::SchedulerOptions scheduler_options() {
  farm::SchedulerOptions options;
  options.data_dir = farm::fuzz::scratch_dir() / "scheduler";
  options.log_level = farm::LogLevel::off;
  // Registered workers that never answer are dropped quickly, so RegisterWorker calls do not
  // pile up workers for the whole run.
  options.heartbeat_interval = milliseconds(100);
  options.probe_interval = milliseconds(100);
  return options;
}

class InProcessScheduler {
 public:
  InProcessScheduler() : core_(scheduler_options()), front_door_(core_), service_(front_door_) {
    grpc::ServerBuilder builder;
    builder.RegisterService(&service_);
    server_ = builder.BuildAndStart();
    stub_ = v1::Scheduler::NewStub(server_->InProcessChannel(grpc::ChannelArguments()));
    for (const auto& entry : std::filesystem::directory_iterator(std::string(FARM_SOURCE_DIR) + "/jobs/assets")) {
      if (entry.is_regular_file()) upload(read_file(entry.path()));
    }
  }
  ~InProcessScheduler() {
    server_->Shutdown(std::chrono::system_clock::now() + milliseconds(200));
    core_.stop();
  }

  void call(std::uint8_t rpc, std::string_view body);

 private:
  void upload(const std::string& bytes) {
    grpc::ClientContext context;
    v1::UploadAssetResponse response;
    auto writer = stub_->UploadAsset(&context, &response);
    v1::UploadAssetRequest header;
    header.mutable_header()->set_sha256(farm::sha256_hex(bytes));
    header.mutable_header()->set_size(bytes.size());
    v1::UploadAssetRequest data;
    data.set_data(bytes);
    writer->Write(header);
    writer->Write(data);
    writer->WritesDone();
    if (!writer->Finish().ok()) farm::fuzz::property_failed("uploading an example asset failed");
  }

  // "@" -> the last job submitted.
  void resolve(std::string* job_id) const {
    if (*job_id == "@") *job_id = last_job_;
  }

  template <typename Request>
  bool parse(Request& request, std::string_view body) const {
    return request.ParseFromArray(body.data(), static_cast<int>(body.size()));
  }

  farm::SchedulerCore core_;
  farm::SchedulerFrontDoor front_door_;
  farm::SchedulerService service_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
  std::string last_job_;
};

// Every call is given a deadline, so a handler that waits forever shows up as a status, and the
// fuzzer's -timeout names it.
std::unique_ptr<grpc::ClientContext> context_with_deadline() {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  return context;
}

void InProcessScheduler::call(std::uint8_t rpc, std::string_view body) {
  auto context = context_with_deadline();
  switch (rpc % 12) {
    case 0: {
      v1::SubmitJobRequest request;
      v1::SubmitJobResponse response;
      if (!parse(request, body)) return;
      if (stub_->SubmitJob(context.get(), request, &response).ok()) {
        last_job_ = response.job().job_id();
        v1::CancelJobRequest cancel;
        cancel.set_job_id(last_job_);
        v1::CancelJobResponse cancelled;
        auto cancel_context = context_with_deadline();
        (void)stub_->CancelJob(cancel_context.get(), cancel, &cancelled);
      }
      return;
    }
    case 1: {
      v1::GetJobRequest request;
      v1::Job response;
      if (!parse(request, body)) return;
      resolve(request.mutable_job_id());
      (void)stub_->GetJob(context.get(), request, &response);
      return;
    }
    case 2: {
      v1::ListJobsRequest request;
      v1::ListJobsResponse response;
      if (!parse(request, body)) return;
      (void)stub_->ListJobs(context.get(), request, &response);
      return;
    }
    case 3: {
      v1::WatchJobRequest request;
      if (!parse(request, body)) return;
      resolve(request.mutable_job_id());
      auto reader = stub_->WatchJob(context.get(), request);
      v1::JobEvent event;
      // The snapshot, and then the client goes away, which the handler must notice.
      (void)reader->Read(&event);
      context->TryCancel();
      (void)reader->Finish();
      return;
    }
    case 4: {
      v1::CancelJobRequest request;
      v1::CancelJobResponse response;
      if (!parse(request, body)) return;
      resolve(request.mutable_job_id());
      (void)stub_->CancelJob(context.get(), request, &response);
      return;
    }
    case 5: {
      v1::GetResultRequest request;
      if (!parse(request, body)) return;
      resolve(request.mutable_job_id());
      auto reader = stub_->GetResult(context.get(), request);
      v1::FileChunk chunk;
      while (reader->Read(&chunk)) {
      }
      (void)reader->Finish();
      return;
    }
    case 6: {
      v1::UploadAssetResponse response;
      auto writer = stub_->UploadAsset(context.get(), &response);
      while (body.size() >= 2) {
        const std::size_t n = static_cast<std::uint8_t>(body[0]) | static_cast<std::size_t>(static_cast<std::uint8_t>(body[1])) << 8;
        body.remove_prefix(2);
        v1::UploadAssetRequest part;
        if (!parse(part, body.substr(0, n))) break;
        body.remove_prefix(std::min(n, body.size()));
        if (!writer->Write(part)) break;
      }
      writer->WritesDone();
      (void)writer->Finish();
      return;
    }
    case 7: {
      v1::HasAssetsRequest request;
      v1::HasAssetsResponse response;
      if (!parse(request, body)) return;
      (void)stub_->HasAssets(context.get(), request, &response);
      return;
    }
    case 8: {
      v1::GetAssetRequest request;
      if (!parse(request, body)) return;
      auto reader = stub_->GetAsset(context.get(), request);
      v1::AssetChunk chunk;
      while (reader->Read(&chunk)) {
      }
      (void)reader->Finish();
      return;
    }
    case 9: {
      v1::RegisterWorkerRequest request;
      v1::RegisterWorkerResponse response;
      if (!parse(request, body)) return;
      (void)stub_->RegisterWorker(context.get(), request, &response);
      return;
    }
    case 10: {
      v1::HeartbeatRequest request;
      v1::HeartbeatResponse response;
      if (!parse(request, body)) return;
      (void)stub_->Heartbeat(context.get(), request, &response);
      return;
    }
    default: {
      // The example jobs' files are held: the plan reads the model and its library.
      v1::PlanSubmissionRequest request;
      v1::PlanSubmissionResponse response;
      if (!parse(request, body)) return;
      (void)stub_->PlanSubmission(context.get(), request, &response);
      return;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // Made on first use and kept for the run: a scheduler per input would spend the time on
  // SQLite and threads instead of the handlers.
  static auto* scheduler = [] {
    farm::set_log_level("off");
    // Protobuf logs every string field of invalid UTF-8 it refuses to parse: thousands of lines
    // a second of fuzzing, none of them a finding (the parse fails, and the input is skipped).
    google::protobuf::SetLogHandler(nullptr);
    return new InProcessScheduler();
  }();
  scheduler->call(data[0], farm::fuzz::as_bytes(data + 1, size - 1));
  return 0;
}
