#include "server/cli/worker_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <grpcpp/grpcpp.h>
#include <signal.h>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "proto/farm.grpc.pb.h"

#include "renderer/render_settings.h"
#include "renderer/scene/input_error.h"
#include "renderer/scene/job_limits.h"
#include "server/cli/log_level_option.h"
#include "server/cli/server_security_flags.h"
#include "server/common/listen_policy.h"
#include "server/common/network_address.h"
#include "server/cli/version.h"
#include "server/common/farm_server.h"
#include "server/common/server_shutdown.h"

namespace farm {

namespace {

// Calls in flight get this long to finish after SIGINT/SIGTERM before they are cancelled; a
// cancelled render stops within milliseconds, and a call still running kShutdownUnwind later
// (preparing a scene, which cannot be interrupted) is abandoned: the worker is gone within 2 s.
constexpr auto kShutdownGrace = std::chrono::milliseconds(1400);
constexpr auto kShutdownUnwind = std::chrono::milliseconds(400);
// A request carries the job file (at most 16 MiB) and, for a worker without --scheduler, the
// job's files inline (RenderTileRequest.assets).
constexpr int kMaxRequestBytes = 1 << 30;

// With --scheduler, the worker registers itself with each scheduler (Scheduler.RegisterWorker)
// and heartbeats until stopped; registers again when the scheduler forgot it (restarted), retries
// while it is away. A scheduler without RegisterWorker (UNIMPLEMENTED) is left alone: assets are
// all it serves. `registered` is told the scheduler's id at each registration.
class Registration {
 public:
  Registration(const std::string& scheduler, const ClientIdentity& identity, std::string address, int threads,
               std::function<void(const std::string& scheduler_id)> registered)
      : scheduler_(scheduler), address_(std::move(address)), threads_(threads), registered_(std::move(registered)),
        stub_(v1::Scheduler::NewStub(open_channel(scheduler, identity))),
        thread_([this] { loop(); }) {}
  ~Registration() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
      // A call to a scheduler that does not answer would hold the shutdown for its deadline.
      if (call_) call_->TryCancel();
    }
    wake_.notify_all();
    thread_.join();
  }

 private:
  bool sleep(std::chrono::milliseconds d) {
    std::unique_lock lock(mutex_);
    return !wake_.wait_for(lock, d, [&] { return stop_; });
  }

  void loop() {
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
        Registration& r;
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

  std::string scheduler_, address_;
  int threads_;
  std::function<void(const std::string&)> registered_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  grpc::ClientContext* call_ = nullptr;  // the call in flight, under mutex_
  std::thread thread_;
};

// Where the scheduler reaches this worker: the listening host, or this machine's name when it
// listens on every interface.
std::string advertised_address(const std::string& listen, int port) {
  std::string host = host_of(listen);
  if (host.empty() || host == "0.0.0.0" || host == "[::]" || host == "::") {
    char name[256] = {};
    ::gethostname(name, sizeof name - 1);
    host = name;
  }
  return fmt::format("{}:{}", host, port);
}

}  // namespace

int run_worker_command(const WorkerCommandOptions& command) {
  WorkerOptions options = command.worker;
  if (options.cache_dir.empty()) {
    options.cache_dir = std::filesystem::temp_directory_path() / "farm-worker-cache";
  }
  std::filesystem::create_directories(options.cache_dir);
  options.cache_dir = std::filesystem::canonical(options.cache_dir);

  // SIGINT and SIGTERM are blocked before gRPC starts its threads (they inherit the mask) and
  // taken synchronously with sigwait below, so no handler runs in signal context.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  // Every file is read and the listen policy applied before anything starts (after the signal
  // mask: making credentials starts gRPC's threads, which must inherit it).
  const ServerSecurity security = make_server_security(command.security, options.listen, "farm worker");
  options.access = security.access;
  options.scheduler_identity = security.outgoing;

  WorkerService service(options);
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(options.listen, security.credentials, &port);
  builder.SetMaxReceiveMessageSize(kMaxRequestBytes);
  builder.RegisterService(&service);
  std::unique_ptr<FarmServer> server = FarmServer::start(builder, v1::Worker::service_full_name());
  if (!server || port == 0) throw InputError(fmt::format("cannot listen on '{}'", options.listen));

  print_security_warnings(security);
  fmt::print("worker listening on {}:{}\n", host_of(options.listen), port);
  fmt::print("  {} render threads, cache {} (at most {} scenes, ~{} MiB){}\n", service.threads(),
             options.cache_dir.string(), options.max_scenes, options.cache_memory_mb,
             options.schedulers.empty() ? "" : ", serving scheduler " + fmt::format("{}", fmt::join(options.schedulers, ", ")));
  std::fflush(stdout);
  std::vector<std::unique_ptr<Registration>> registrations;
  for (const std::string& scheduler : options.schedulers) {
    registrations.push_back(std::make_unique<Registration>(
        scheduler, security.outgoing, advertised_address(options.listen, port), service.threads(),
        [&service, scheduler](const std::string& id) { service.scheduler_registered(id, scheduler); }));
  }

  int signal_number = 0;
  sigwait(&signals, &signal_number);
  fmt::print("worker: {}, shutting down\n", signal_number == SIGINT ? "SIGINT" : "SIGTERM");
  std::fflush(stdout);
  registrations.clear();
  if (!shut_down_within(*server, kShutdownGrace, kShutdownUnwind)) {
    // Safe to leave mid-call: the worker's files (blobs, laid-out scenes) are written under a
    // temporary name and renamed into place, and the scheduler sends an abandoned tile again.
    fmt::print("worker: calls still running after the grace period, exiting without them\n");
    exit_abandoning_calls(0);
  }
  return 0;
}

void add_worker_command(CLI::App& app, CommandTable& commands) {
  auto command = std::make_shared<WorkerCommandOptions>();
  WorkerOptions* o = &command->worker;
  o->listen = kDefaultWorkerListen;
  CLI::App* worker = app.add_subcommand(
      "worker", "Serve farm.v1.Worker (RenderTile) plus gRPC health and reflection");
  worker->add_option("--listen", o->listen,
                     "Address to serve on, HOST:PORT (port 0 picks a free port; the address is "
                     "printed as 'worker listening on HOST:PORT'). Beyond loopback it needs --tokens "
                     "or --tls-ca, or --insecure")
      ->capture_default_str();
  worker->add_option("--threads", o->threads, "Render threads shared by all calls (0 = all cores)")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  worker->add_option("--scheduler", o->schedulers,
                     "Scheduler HOST:PORT to register with and fetch the assets this worker lacks "
                     "from (by SHA-256); several, comma-separated or repeated, for a farm of "
                     "several schedulers on one store: the worker serves them all, fetching a "
                     "call's assets from the scheduler that sent it. Without it, the worker "
                     "registers nowhere (give it to `farm scheduler --worker`) and a job whose "
                     "assets are not in the cache fails with FAILED_PRECONDITION")
      ->delimiter(',');
  worker->add_option("--cache-dir", o->cache_dir,
                     "Folder for fetched assets (blobs/<sha256>) and laid-out scenes "
                     "(scenes/<scene hash>/) (default: <temp>/farm-worker-cache)");
  worker->add_option("--max-scenes", o->max_scenes, "Prepared scenes kept in memory (LRU)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  worker->add_option("--cache-memory", o->cache_memory_mb,
                     "Approximate memory budget of the prepared scenes, MiB (LRU)")
      ->check(CLI::Range(1, 1 << 24))
      ->capture_default_str();
  worker->footer("Each RenderTile call renders its rectangle on all render threads, in 16x16 "
                 "sub-tiles shared with concurrent calls; a call stops when its client cancels "
                 "or its deadline passes. Scenes are prepared once per scene hash. SIGINT or "
                 "SIGTERM shut the worker down cleanly.");
  add_server_security_flags(*worker, command->security,
                            "the scheduler (give it a token with the worker role)");
  add_log_level_option(*worker, "info");
  commands.add(worker, [command] { return run_worker_command(*command); });
}

}  // namespace farm
