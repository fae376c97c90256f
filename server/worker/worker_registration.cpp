#include "server/worker/worker_registration.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "renderer/job/render_settings.h"
#include "server/common/network_address.h"
#include "server/common/version.h"

namespace farm {

WorkerRegistration::WorkerRegistration(const std::string& scheduler, const ClientIdentity& identity,
                                       std::string address, int threads, std::vector<std::string> tags,
                                       std::function<void(const std::string& scheduler_id)> registered)
    : scheduler_(scheduler), address_(std::move(address)), threads_(threads), tags_(std::move(tags)),
      registered_(std::move(registered)),
      stub_(v1::Scheduler::NewStub(open_channel(scheduler, identity))),
      thread_([this] { loop(); }) {}

WorkerRegistration::~WorkerRegistration() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    // A call to a scheduler that does not answer would hold the shutdown for its deadline.
    if (call_) call_->TryCancel();
  }
  wake_.notify_all();
  thread_.join();
}

bool WorkerRegistration::sleep(std::chrono::milliseconds d) {
  std::unique_lock lock(mutex_);
  return !wake_.wait_for(lock, d, [&] { return stop_; });
}

void WorkerRegistration::loop() {
  std::string id;
  std::string refusal;  // the last UNAUTHENTICATED or PERMISSION_DENIED message
  std::chrono::milliseconds interval(1000);
  while (true) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    {
      std::lock_guard lock(mutex_);
      if (stop_) return;
      call_ = &context;
    }
    // Cleared before `context` goes: the destructor cancels only a call still in flight.
    struct Clear {
      WorkerRegistration& r;
      ~Clear() {
        std::lock_guard lock(r.mutex_);
        r.call_ = nullptr;
      }
    } clear{*this};
    if (id.empty()) {
      v1::RegisterWorkerRequest request;
      request.set_address(address_);
      request.set_threads(threads_);
      for (std::string_view e : kEngineNames) request.add_engines(std::string(e));
      for (const std::string& tag : tags_) request.add_tags(tag);
      char host[256] = {};
      ::gethostname(host, sizeof host - 1);
      request.set_hostname(host);
      request.set_version(std::string(kFarmVersion));
      v1::RegisterWorkerResponse response;
      const grpc::Status status = stub_->RegisterWorker(&context, request, &response);
      if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED) return;
      if (status.error_code() == grpc::StatusCode::UNAUTHENTICATED ||
          status.error_code() == grpc::StatusCode::PERMISSION_DENIED) {
        // Retried, since the operator may fix the tokens file; said again only when it changes.
        if (status.error_message() != refusal) {
          refusal = status.error_message();
          fmt::print(stderr, "worker: the scheduler {} refused the registration: {}\n", scheduler_, refusal);
          std::fflush(stderr);
        }
      }
      if (status.ok()) {
        id = response.worker_id();
        interval = std::chrono::milliseconds(std::max(50u, response.heartbeat_interval_ms()));
        if (!response.scheduler_id().empty()) registered_(response.scheduler_id());
        fmt::print("worker: registered with the scheduler {}{} as {}\n", scheduler_,
                   response.scheduler_id().empty() ? "" : " (" + response.scheduler_id() + ")", id);
        std::fflush(stdout);
      }
    } else {
      v1::HeartbeatRequest request;
      request.set_worker_id(id);
      v1::HeartbeatResponse response;
      const grpc::Status status = stub_->Heartbeat(&context, request, &response);
      if (status.ok() && response.register_again()) id.clear();
    }
    if (!sleep(interval)) return;
  }
}

// Where the scheduler reaches this worker: the listening host, or this machine's name when it
// listens on every interface.
std::string advertised_worker_address(const std::string& listen, int port) {
  std::string host = host_of(listen);
  if (host.empty() || host == "0.0.0.0" || host == "[::]" || host == "::") {
    char name[256] = {};
    ::gethostname(name, sizeof name - 1);
    host = name;
  }
  return fmt::format("{}:{}", host, port);
}

}  // namespace farm
