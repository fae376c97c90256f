#include "server/worker_command.h"

#include <fmt/format.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "renderer/scene/input_error.h"

namespace farm {

namespace {

// Calls in flight get this long to finish after SIGINT/SIGTERM before they are cancelled.
constexpr auto kShutdownGrace = std::chrono::seconds(2);
// Job files are at most 16 MiB; the rest of a request is small.
constexpr int kMaxRequestBytes = 32 << 20;

std::string host_of(const std::string& address) {
  const std::size_t colon = address.rfind(':');
  return colon == std::string::npos ? address : address.substr(0, colon);
}

}  // namespace

int run_worker_command(const WorkerOptions& given) {
  WorkerOptions options = given;
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

  WorkerService service(options);
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(options.listen, grpc::InsecureServerCredentials(), &port);
  builder.SetMaxReceiveMessageSize(kMaxRequestBytes);
  builder.RegisterService(&service);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) throw InputError(fmt::format("cannot listen on '{}'", options.listen));

  fmt::print("worker listening on {}:{}\n", host_of(options.listen), port);
  fmt::print("  {} render threads, cache {} (at most {} scenes, ~{} MiB){}\n", service.threads(),
             options.cache_dir.string(), options.max_scenes, options.cache_memory_mb,
             options.scheduler.empty() ? "" : ", assets from scheduler " + options.scheduler);
  std::fflush(stdout);

  int signal_number = 0;
  sigwait(&signals, &signal_number);
  fmt::print("worker: {}, shutting down\n", signal_number == SIGINT ? "SIGINT" : "SIGTERM");
  std::fflush(stdout);
  server->Shutdown(std::chrono::system_clock::now() + kShutdownGrace);
  server->Wait();
  return 0;
}

}  // namespace farm
