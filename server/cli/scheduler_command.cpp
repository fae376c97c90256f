#include "server/cli/scheduler_command.h"

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "renderer/util/input_error.h"
#include "server/cli/duration_option.h"
#include "server/cli/log_level_option.h"
#include "server/cli/server_security_flags.h"
#include "server/common/farm_server.h"
#include "server/common/listen_policy.h"
#include "server/common/network_address.h"
#include "server/common/server_shutdown.h"
#include "server/scheduler/front_door.h"
#include "server/scheduler/http/dashboard_server.h"
#include "server/scheduler/http/webhook_notifier.h"
#include "server/scheduler/scheduler_core.h"
#include "server/scheduler/scheduler_service.h"
#include "server/scheduler/store/postgres_connection.h"

namespace farm {

namespace {

constexpr int kMaxRequestBytes = 64 << 20;

std::chrono::milliseconds ms(double seconds) {
  return std::chrono::milliseconds(static_cast<std::int64_t>(seconds * 1000.0));
}

}  // namespace

int run_scheduler_command(const SchedulerCommandOptions& o) {
  const StopSignals stop_signals;  // before gRPC starts its threads (server_shutdown.h)
  // Every file is read and the listen policy applied before anything starts (after the signal
  // mask: making credentials starts gRPC's threads, which must inherit it).
  ServerSecurity security = make_server_security(o.security, o.listen, "farm scheduler");

  if (!o.store.empty() && !is_postgres_url(o.store)) {
    throw InputError(fmt::format("--store '{}': give a postgresql://USER@HOST:PORT/DATABASE URL (without "
                                 "--store the job store is SQLite, jobs.db in --data-dir)",
                                 o.store));
  }
  SchedulerOptions options;
  options.data_dir = o.data_dir;
  options.store = o.store;
  options.lease = ms(o.lease_s);
  options.tile_deadline = ms(o.tile_deadline_s);
  options.max_attempts = o.max_attempts;
  options.upload_idle_timeout = ms(o.upload_idle_timeout_s);
  if (!o.keep_finished.empty()) options.keep_finished = parse_duration(o.keep_finished, "--keep-finished");
  if (!o.notify_url.empty()) parse_webhook_url(o.notify_url);  // refused before anything starts
  options.max_lost_worker_attempts = o.max_lost_worker_attempts;
  options.tiles_per_worker = o.tiles_per_worker;
  options.batch_target = std::chrono::milliseconds(o.batch_ms);
  options.heartbeat_interval = ms(o.heartbeat_interval_s);
  options.exr_type = o.float_exr ? ExrPixelType::Float : ExrPixelType::Half;
  options.verify_fraction = o.verify_fraction;
  options.remote_verify_fraction = o.remote_verify_fraction;
  options.limits = o.limits;
  // New jobs' scenes are loaded by this binary again, as `farm check-scene`, under the limits.
  options.scene_check_program = std::filesystem::read_symlink("/proc/self/exe");
  SchedulerCore core(options);
  // Held by the core's listener too, so that it outlives every event the core publishes.
  std::shared_ptr<WebhookNotifier> notifier;
  if (!o.notify_url.empty()) {
    notifier = std::make_shared<WebhookNotifier>(o.notify_url, core.scheduler_id(), core.log());
    core.listen([notifier](const v1::JobEvent& event) { notifier->enqueue(event); });
  }

  // One front door, its checks inside; gRPC and the dashboard are adapters over it.
  SchedulerFrontDoor front_door(core, SchedulerAccess{security.access, security.outgoing, o.max_priority});
  SchedulerService service(front_door);
  std::unique_ptr<DashboardServer> dashboard;
  if (!o.http.empty()) {
    // The gRPC port's rules: beyond loopback only with tokens (or --insecure); HTTPS when the
    // scheduler has a certificate.
    // A browser presents no client certificate: only tokens count as authentication here.
    for (const std::string& warning : check_listen_security({.listen = o.http,
                                                             .tokens = security.access.requires_tokens(),
                                                             .client_certificates = false,
                                                             .tls = o.security.tls.has_certificate(),
                                                             .insecure = o.security.insecure},
                                                            "the scheduler's dashboard (--http)")) {
      security.warnings.push_back(warning);
    }
    dashboard = std::make_unique<DashboardServer>(
        front_door,
        DashboardOptions{.listen = o.http, .tls_cert = o.security.tls.cert, .tls_key = o.security.tls.key,
                         .host_names = o.http_hosts},
        core.log());
  }
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(o.listen, security.credentials, &port);
  builder.SetMaxReceiveMessageSize(kMaxRequestBytes);
  builder.RegisterService(&service);
  std::unique_ptr<FarmServer> server = FarmServer::start(builder, v1::Scheduler::service_full_name());
  if (!server || port == 0) throw InputError(fmt::format("cannot listen on '{}'", o.listen));
  // Added once the port is known: a scheduler listed as its own worker would answer every unit
  // UNIMPLEMENTED (a plain slip: --worker given the --listen address).
  for (const std::string& address : o.workers) {
    if (names_own_server(address, host_of(o.listen), port)) {
      throw InputError(fmt::format("--worker {}: that is this scheduler's own address (it listens on {}:{}); give "
                                   "the address a `farm worker` listens on",
                                   address, host_of(o.listen), port));
    }
    core.add_worker(std::make_shared<RemoteTileWorker>(
        address, WorkerLink{security.outgoing, std::string(), &core.grants()}));
  }

  print_security_warnings(security);
  fmt::print("scheduler listening on {}:{}\n", host_of(o.listen), port);
  fmt::print("  data dir {}, job store {}, {} static worker(s), unit deadline {} s, {} attempts a unit\n",
             o.data_dir.string(), core.store().describe(), o.workers.size(), o.tile_deadline_s, o.max_attempts);
  if (core.store().is_shared()) fmt::print("  scheduler {}, lease {} s\n", core.scheduler_id(), o.lease_s);
  if (!o.keep_finished.empty()) fmt::print("  finished jobs kept {} after they end, then deleted\n", o.keep_finished);
  if (notifier) fmt::print("  each job's end posted to {}\n", parse_webhook_url(o.notify_url).shown());
  fmt::print("  {}, {}\n", security.access.requires_tokens() ? "tokens required" : "no tokens",
             o.security.tls.has_certificate() ? (o.security.tls.ca.empty() ? "TLS" : "mTLS") : "plain text");
  if (dashboard) {
    fmt::print("dashboard on {}://{}:{}/\n", dashboard->scheme(), host_of(o.http), dashboard->port());
  }
  std::fflush(stdout);

  fmt::print("scheduler: {}, shutting down\n", stop_signals.wait());
  std::fflush(stdout);
  // Dispatch stops first: calls to workers cancelled, their tiles queued again in the store (no
  // attempt counted). Once the server shuts down it refuses the heartbeats and asset fetches
  // those calls depend on, and its grace period outlasts a worker's heartbeat limit: a worker
  // would be dropped, or fail its tiles, and every call in flight be counted lost. The clients'
  // calls (the store's, the events') still get their grace.
  if (dashboard) dashboard->stop();  // its event streams end, its calls finish
  core.stop();
  if (notifier) notifier->stop();
  const bool drained = shut_down_within(*server);
  if (!drained) {
    // Safe to leave mid-call. The job store is SQLite in WAL mode, which a process that dies in
    // the middle of a transaction leaves as it was before it (the next open rolls the unfinished
    // transaction back), or PostgreSQL, which rolls back the transaction of a connection that
    // closed: an abandoned SubmitJob has queued its job entirely or not at all, and its client
    // was never told OK. Every file (assets, laid-out scenes, tiles, results) is written
    // under a temporary name and renamed into place, so none is left half-written.
    fmt::print("scheduler: calls still running after the grace period, exiting without them\n");
    exit_abandoning_calls(0);
  }
  return 0;
}

void add_scheduler_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<SchedulerCommandOptions>();
  CLI::App* s = app.add_subcommand(
      "scheduler", "Serve farm.v1.Scheduler: jobs in, units to workers, merged EXR + PNG out");
  s->add_option("--listen", o->listen,
                "Address to serve on, HOST:PORT (port 0 picks a free port; the address is printed "
                "as 'scheduler listening on HOST:PORT'); the clients' default is localhost:50051. "
                "Beyond loopback it needs --tokens or --tls-ca, or --insecure")
      ->capture_default_str();
  s->add_option("--data-dir", o->data_dir,
                "Folder for the job store (jobs.db, SQLite WAL), uploaded assets, finished tiles "
                "and results; a restarted scheduler resumes the jobs it finds there")
      ->required();
  s->add_option("--store", o->store,
                "The job store: a PostgreSQL database, postgresql://USER@HOST:PORT/DATABASE (a libpq "
                "URL; a password is better kept in ~/.pgpass or PGPASSWORD than in the URL). Without "
                "it: SQLite, jobs.db in --data-dir. The schema is made, or upgraded, at start")
      ->envname("FARM_STORE");
  s->add_option("--lease", o->lease_s,
                "With --store: seconds this scheduler's hold on the units it hands out lasts unless "
                "renewed (every third of it). Several schedulers may share one store and --data-dir "
                "(a shared folder): the units of one that dies are rendered by the others, or by "
                "its successor, once its lease runs out")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  s->add_option("--worker", o->workers,
                "A `farm worker` HOST:PORT to send units to (repeat for more); workers may also "
                "register themselves (farm worker --scheduler)");
  s->add_option("--tile-deadline", o->tile_deadline_s,
                "Seconds a worker gets per unit of a call before the call's units are given to "
                "another; a worker that misses it gets no more units until it answers a health check")
      ->check(CLI::Range(0.05, 86400.0))
      ->capture_default_str();
  s->add_option("--max-attempts", o->max_attempts,
                "Failed attempts of one unit (deadline, error, bad result) before its job fails; a "
                "worker lost while rendering it counts under --max-lost-worker-attempts instead")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  s->add_option("--http", o->http,
                "Serve the web dashboard, its JSON API (/api/v1/) and /metrics on HOST:PORT (port 0: any "
                "free one; the address is printed). Same tokens and roles as the gRPC API; beyond "
                "loopback it needs --tokens; HTTPS with --tls-cert")
      ->envname("FARM_HTTP");
  s->add_option("--http-host", o->http_hosts,
                "A DNS name the dashboard answers to (repeatable), as browsers reach it: besides "
                "--http's own host, localhost and IP addresses, a request naming any other Host is "
                "refused (421), so that a DNS name rebound to this machine reaches nothing");
  s->add_option("--notify-url", o->notify_url,
                "POST a JSON event ({\"event\": \"job.succeeded\"|\"job.failed\"|\"job.cancelled\", "
                "\"scheduler\", \"job\"}) to this http(s) URL when a job ends: a CI's or a chat's "
                "webhook. Retried with backoff (1 s doubling to 60 s, 8 attempts); never holds dispatch. "
                "Logs show its origin only (a chat's webhook keeps its secret in the path); "
                "FARM_NOTIFY_URL keeps it out of the process list too")
      ->envname("FARM_NOTIFY_URL");
  s->add_option("--keep-finished", o->keep_finished,
                "Delete jobs (from the store, with their tiles and result files) this long after "
                "they succeeded, failed or were cancelled: 90s, 30m, 12h, 7d, 2w. Running and "
                "queued jobs are never deleted. Default: keep every job")
      ->envname("FARM_KEEP_FINISHED");
  s->add_option("--max-lost-worker-attempts", o->max_lost_worker_attempts,
                "Workers one unit may lose while rendering it (the call ended UNAVAILABLE: its process "
                "died; or it missed its heartbeats) before its job fails: counted apart from "
                "--max-attempts, and bounded so that a unit that crashes every worker it is sent to "
                "still ends its job")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  s->add_option("--tiles-per-worker", o->tiles_per_worker,
                "Calls in flight per worker (its slots), so that none idles between calls")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  s->add_option("--batch-ms", o->batch_ms,
                "Rendering time one call aims at: once a job's first tiles are timed (the worker's "
                "CPU time per tile over its threads), consecutive tiles of a row go out together "
                "in batches about this long (smaller near the end "
                "of a job; a tile that failed goes alone); 0 sends one tile per call")
      ->check(CLI::Range(0, 600000))
      ->capture_default_str();
  s->add_option("--heartbeat-interval", o->heartbeat_interval_s,
                "Seconds between registered workers' heartbeats; one silent for 3 is dropped")
      ->check(CLI::Range(0.05, 3600.0))
      ->capture_default_str();
  s->add_option("--verify-fraction", o->verify_fraction,
                "Spot checks: this fraction of each job's tiles (at least one when above 0, given "
                "a second worker) is rendered again on another worker and must come back "
                "bit-identical; a worker whose pixels differ, by a third worker's judgement, is "
                "quarantined and its results for unfinished jobs are rendered again")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  s->add_option("--verify-remote-fraction", o->remote_verify_fraction,
                "The same for workers on another host (not localhost, 127.x or ::1), when higher than "
                "--verify-fraction: on by default, since their replies cross a network; 2% of their units "
                "rendered twice, at least one a job. 0: only --verify-fraction")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  s->add_flag("--float", o->float_exr, "Write 32-bit float EXRs instead of half");
  add_server_security_flags(*s, o->security, "workers (give it a token with the scheduler role)");
  s->add_option("--max-priority", o->max_priority,
                "Highest job priority a caller without the admin role may ask for")
      ->capture_default_str();
  s->footer("Jobs run in priority order, then in submission order. Each frame, once its tiles are "
            "done, is merged into <data-dir>/results/<job>/<frame>/ (EXR with the job's AOV layers + "
            "PNG preview; a still is frame 0), fetched with GetResult. SIGINT or SIGTERM stop it cleanly: tiles in "
            "flight go back to the queue.\n\nSecurity: it listens on loopback unless --listen says "
            "otherwise. With --tokens, calls need a token: 'submit' callers see and act on their "
            "own jobs, 'read' sees every job, 'admin' does everything, workers need 'worker' to "
            "register and fetch the assets of the tiles they are given. The tokens file holds "
            "only SHA-256 hashes of the tokens.");
  s->add_option("--max-job-bytes", o->limits.max_job_bytes,
                "Largest job text (JobSpec.job_json) SubmitJob takes, in bytes (RESOURCE_EXHAUSTED above)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{kMaxRequestBytes} - (1 << 20)))
      ->capture_default_str();
  s->add_option("--max-tiles-per-job", o->limits.max_tiles_per_job,
                "Most units of one job: frames x sample passes x the tiles of a frame's grid "
                "(ceil(width/tile_size) x ceil(height/tile_size))")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 28))
      ->capture_default_str();
  s->add_option("--max-work", o->limits.max_work,
                "Most width x height x spp x path length (1 for raster, max_depth + 1 for the ray "
                "engines, unbounded counted as 17) of one job")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  s->add_option("--max-embree-rays", o->limits.max_embree_rays,
                "Most validate.embree_rays of one job (traced in the scheduler at merge)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{1} << 40))
      ->capture_default_str();
  s->add_option("--max-asset-bytes", o->limits.max_asset_bytes, "Largest asset file, in bytes")
      ->capture_default_str();
  s->add_option("--max-job-asset-bytes", o->limits.max_job_asset_bytes,
                "Most bytes of one job's assets together")
      ->capture_default_str();
  s->add_option("--max-asset-store-bytes", o->limits.max_asset_store_bytes,
                "Most bytes the scheduler's asset store holds together (UploadAsset is "
                "RESOURCE_EXHAUSTED beyond; one owner's uploads in flight hold at most a quarter of it); "
                "0 for no limit")
      ->capture_default_str();
  s->add_option("--upload-idle-timeout", o->upload_idle_timeout_s,
                "Seconds an UploadAsset stream may send nothing before it is ended and its share of the "
                "quota freed")
      ->check(CLI::Range(0.05, 86400.0))
      ->capture_default_str();
  s->add_option("--max-scene-memory", o->limits.max_scene_memory,
                "Memory, in bytes, that loading a new job's models and building its scene may take "
                "at submit (done in a child process; RESOURCE_EXHAUSTED above)")
      ->check(CLI::Range(std::uint64_t{256} << 20, std::uint64_t{1} << 50))
      ->capture_default_str();
  s->add_option("--max-scene-seconds", o->limits.max_scene_seconds,
                "Seconds that loading a new job's models and building its scene may take at submit "
                "(the child process is killed after that; RESOURCE_EXHAUSTED)")
      ->check(CLI::Range(0.1, 86400.0))
      ->capture_default_str();
  s->add_option("--max-scene-checks", o->limits.max_scene_checks,
                "Scene checks (child processes) at once; others wait up to --max-scene-seconds for "
                "one to end. Also the submissions planned at once (PlanSubmission, at most 64; "
                "others wait 30 s). 0: half the machine's hardware threads, at least 1")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  add_log_level_option(*s, "info");
  commands.add(s, [o] { return run_scheduler_command(*o); });
}

}  // namespace farm
