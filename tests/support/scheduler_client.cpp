#include "tests/support/scheduler_client.h"

#include <grpcpp/grpcpp.h>

#include <fstream>
#include <regex>
#include <thread>

#include "server/common/sha256.h"
#include "tests/support/job_specs.h"

namespace farm::test {

namespace {
constexpr auto kStartTimeout = std::chrono::seconds(30);
constexpr auto kCallTimeout = std::chrono::seconds(30);

void set_deadline(grpc::ClientContext& context, std::chrono::milliseconds timeout = kCallTimeout) {
  context.set_deadline(std::chrono::system_clock::now() + timeout);
}
}  // namespace

SchedulerProcess::SchedulerProcess(const std::filesystem::path& data_dir,
                                   const std::vector<std::string>& extra_args)
    : process_([&] {
        std::vector<std::string> argv{FARM_BINARY, "scheduler", "--listen", "127.0.0.1:0",
                                      "--data-dir", data_dir.string()};
        argv.insert(argv.end(), extra_args.begin(), extra_args.end());
        return argv;
      }()),
      address_(wait_for_listening(process_, "scheduler", kStartTimeout)) {}

std::string SchedulerProcess::dashboard_url() {
  const std::regex line(R"(dashboard on (https?://[0-9.]+:[0-9]+)/)");
  const auto until = std::chrono::steady_clock::now() + kStartTimeout;
  std::smatch m;
  while (std::chrono::steady_clock::now() < until) {
    const std::string out = process_.output();
    if (std::regex_search(out, m, line)) return m[1];
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return {};
}

LocalFarm start_local_farm(const std::filesystem::path& dir, int workers, const std::vector<std::string>& scheduler_args) {
  LocalFarm farm;
  farm.scheduler = std::make_unique<SchedulerProcess>(dir / "data", scheduler_args);
  if (farm.scheduler->address().empty()) {
    farm.problem = "the scheduler did not start: ";
    farm.problem += farm.scheduler->process().output();
    return farm;
  }
  for (int i = 1; i <= workers; ++i) {
    std::string cache = "w";
    cache += std::to_string(i);
    auto worker = std::make_unique<WorkerProcess>(
        std::vector<std::string>{"--threads", "1", "--cache-dir", (dir / cache).string(), "--scheduler", farm.address()});
    if (worker->address().empty() ||
        !worker->process().wait_for_line("registered with the scheduler", std::chrono::seconds(20))) {
      farm.problem = "a worker did not start and register: ";
      farm.problem += worker->process().output();
      return farm;
    }
    farm.workers.push_back(std::move(worker));
  }
  return farm;
}

std::unique_ptr<v1::Scheduler::Stub> scheduler_stub(const std::string& address) {
  return scheduler_stub(address, ClientIdentity{});
}

std::unique_ptr<v1::Scheduler::Stub> scheduler_stub(const std::string& address, const ClientIdentity& identity) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  return v1::Scheduler::NewStub(open_channel(address, identity, args));
}

grpc::Status upload_assets(v1::Scheduler::Stub& stub,
                           const std::vector<std::pair<std::string, std::filesystem::path>>& files) {
  for (const auto& [path, file] : files) {
    const std::string bytes = read_file(file);
    const std::string sha = sha256_hex(bytes);
    v1::HasAssetsRequest has;
    has.add_sha256(sha);
    v1::HasAssetsResponse missing;
    {
      grpc::ClientContext context;
      set_deadline(context);
      grpc::Status status = stub.HasAssets(&context, has, &missing);
      if (!status.ok()) return status;
    }
    if (missing.missing_size() == 0) continue;
    grpc::ClientContext context;
    set_deadline(context);
    v1::UploadAssetResponse response;
    auto writer = stub.UploadAsset(&context, &response);
    v1::UploadAssetRequest part;
    part.mutable_header()->set_sha256(sha);
    part.mutable_header()->set_size(bytes.size());
    writer->Write(part);
    for (std::size_t at = 0; at < bytes.size(); at += 4096) {
      v1::UploadAssetRequest data;
      data.set_data(bytes.substr(at, 4096));
      if (!writer->Write(data)) break;
    }
    writer->WritesDone();
    grpc::Status status = writer->Finish();
    if (!status.ok()) return status;
  }
  return grpc::Status::OK;
}

grpc::Status submit(v1::Scheduler::Stub& stub, const v1::JobSpec& spec, v1::Job& job, int priority) {
  grpc::ClientContext context;
  set_deadline(context);
  v1::SubmitJobRequest request;
  *request.mutable_job() = spec;
  request.set_priority(priority);
  v1::SubmitJobResponse response;
  grpc::Status status = stub.SubmitJob(&context, request, &response);
  job = response.job();
  return status;
}

std::optional<v1::Job> get_job(v1::Scheduler::Stub& stub, const std::string& id) {
  grpc::ClientContext context;
  set_deadline(context, std::chrono::seconds(5));
  v1::GetJobRequest request;
  request.set_job_id(id);
  v1::Job job;
  if (!stub.GetJob(&context, request, &job).ok()) return std::nullopt;
  return job;
}

std::optional<v1::Job> wait_for_job(v1::Scheduler::Stub& stub, const std::string& id,
                                    const std::function<bool(const v1::Job&)>& done,
                                    std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (auto job = get_job(stub, id); job && done(*job)) return job;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return std::nullopt;
}

std::vector<v1::JobEvent> watch_job(v1::Scheduler::Stub& stub, const std::string& id,
                                    std::chrono::milliseconds timeout, grpc::Status* status,
                                    const std::function<void()>& subscribed) {
  grpc::ClientContext context;
  set_deadline(context, timeout);
  v1::WatchJobRequest request;
  request.set_job_id(id);
  auto reader = stub.WatchJob(&context, request);
  std::vector<v1::JobEvent> events;
  v1::JobEvent event;
  while (reader->Read(&event)) {
    events.push_back(event);
    if (events.size() == 1 && subscribed) subscribed();
  }
  grpc::Status s = reader->Finish();
  if (status) *status = s;
  return events;
}

grpc::Status fetch_result(v1::Scheduler::Stub& stub, const std::string& id, v1::ResultKind kind,
                          const std::filesystem::path& file, std::optional<int> frame) {
  grpc::ClientContext context;
  set_deadline(context);
  v1::GetResultRequest request;
  request.set_job_id(id);
  request.set_kind(kind);
  if (frame) request.set_frame(*frame);
  auto reader = stub.GetResult(&context, request);
  std::string bytes, sha;
  v1::FileChunk chunk;
  while (reader->Read(&chunk)) {
    if (chunk.offset() == 0) sha = chunk.sha256();
    bytes += chunk.data();
  }
  grpc::Status status = reader->Finish();
  if (!status.ok()) return status;
  if (sha256_hex(bytes) != sha) return {grpc::StatusCode::DATA_LOSS, "sha256 mismatch"};
  std::ofstream(file, std::ios::binary) << bytes;
  return status;
}

}  // namespace farm::test
