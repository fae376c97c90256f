#include "server/cli/worker_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <grpcpp/grpcpp.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "proto/farm.grpc.pb.h"

#include "renderer/job/job_limits.h"
#include "renderer/job/worker_requirements.h"
#include "renderer/job/render_settings.h"
#include "renderer/util/input_error.h"
#include "server/cli/log_level_option.h"
#include "server/cli/server_security_flags.h"
#include "server/common/farm_server.h"
#include "server/common/listen_policy.h"
#include "server/common/network_address.h"
#include "server/common/server_shutdown.h"
#include "server/common/version.h"
#include "server/worker/worker_registration.h"

namespace farm {

namespace {

// A request carries the job file (at most 16 MiB) and, for a worker without --scheduler, the
// job's files inline (RenderTileRequest.assets).
constexpr int kMaxRequestBytes = 1 << 30;

}  // namespace

int run_worker_command(const WorkerCommandOptions& command) {
  WorkerOptions options = command.worker;
  sort_worker_tags(options.tags);
  if (options.tags.size() > kMaxWorkerTags) {
    throw InputError(fmt::format("--tag: {} tags; at most {}", options.tags.size(), kMaxWorkerTags));
  }
  if (options.cache_dir.empty()) {
    options.cache_dir = std::filesystem::temp_directory_path() / "farm-worker-cache";
  }
  std::filesystem::create_directories(options.cache_dir);
  options.cache_dir = std::filesystem::canonical(options.cache_dir);

  const StopSignals stop_signals;  // before gRPC starts its threads (server_shutdown.h)
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
  fmt::print("  {} render threads, cache {} (at most {} scenes, ~{} MiB){}{}\n", service.threads(),
             options.cache_dir.string(), options.max_scenes, options.cache_memory_mb,
             options.schedulers.empty() ? "" : ", serving scheduler " + fmt::format("{}", fmt::join(options.schedulers, ", ")),
             options.tags.empty() ? "" : fmt::format(", tags {}", fmt::join(options.tags, ", ")));
  std::fflush(stdout);
  std::vector<std::unique_ptr<WorkerRegistration>> registrations;
  for (const std::string& scheduler : options.schedulers) {
    registrations.push_back(std::make_unique<WorkerRegistration>(
        scheduler, security.outgoing, advertised_worker_address(options.listen, port), service.threads(), options.tags,
        [&service, scheduler](const std::string& id) { service.scheduler_registered(id, scheduler); }));
  }

  fmt::print("worker: {}, shutting down\n", stop_signals.wait());
  std::fflush(stdout);
  registrations.clear();
  if (!shut_down_within(*server)) {
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
  worker->add_option("--tag", o->tags,
                     "A tag this worker offers the schedulers it registers with (big-mem, course-cg, ...): a job "
                     "whose requirements.tags name tags goes only to workers with every one; repeated or "
                     "comma-separated, at most 16, each letters, digits, '.', '_' and '-'")
      ->delimiter(',')
      ->check(CLI::Validator(
          [](std::string& tag) { return worker_tag_problem(tag).value_or(""); }, "TAG", "worker tag"));
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
