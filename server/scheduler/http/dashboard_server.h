#pragma once
// The scheduler's web side (`farm scheduler --http ADDR`): the dashboard's pages (server/web/,
// compiled in: web_assets.h), a JSON API under /api/v1/ that mirrors the job and worker RPCs, live
// updates by Server-Sent Events, and /metrics in Prometheus's text format. Served by cpp-httplib
// (Debian's libcpp-httplib-dev), over HTTPS with the scheduler's own certificate when it has one.
//
// The API is the RPCs' messages as JSON (protobuf's JSON mapping, proto field names), and every
// call, /metrics and the event streams included, goes through the scheduler's front door
// (front_door.h) for an authenticated caller, so the dashboard checks the same roles and ownership
// as gRPC, in the same code; it holds no other way to the scheduler:
//   GET  /api/v1/jobs?state=running,failed&name=GLOB&id_prefix=HEX&page_size=N&page_token=T
//                                          ListJobsResponse
//   GET  /api/v1/jobs/ID                   Job
//   GET  /api/v1/jobs/ID/log?after=N       GetJobLogResponse
//   POST /api/v1/jobs/ID/cancel|pause|resume|retry|delete   Job, RetryJobResponse, DeleteJobResponse
//   POST /api/v1/jobs/ID/priority  {"priority": N}          Job
//   GET  /api/v1/jobs/ID/live?frame=F      the frame as rendered so far (PNG)
//   GET  /api/v1/jobs/ID/file?kind=exr|preview|video|progressive[&frame=F]   GetResult's file
//   GET  /api/v1/workers                   ListWorkersResponse
//   GET  /api/v1/events[?job=ID]           text/event-stream: `job` events (JobEvent JSON) in order,
//                                          `resync` when the reader fell behind and events were lost
//   GET  /api/v1/whoami, POST /api/v1/login {"token": T}, POST /api/v1/logout
//   GET  /metrics                          Prometheus text (prometheus_text.h); read or admin, since
//                                          it names the workers (as ListWorkers)
//
// Who calls: a scheduler with --tokens wants a token, as an `Authorization: Bearer` header or
// through a login, which sets an HttpOnly, SameSite=Strict session cookie (dashboard_sessions.h).
// Without tokens every caller holds every role, and --http must be a loopback address (or
// --insecure), as for gRPC. A POST must be `Content-Type: application/json` and, when it says
// where it came from (Origin), come from this server's own pages: no other site can make a
// browser act on the farm. Every request must name this server in Host (host_allowlist.h), so a
// rebound DNS name reaches nothing. Bodies are bounded, and so are the event streams open at once.
#include <atomic>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/logger.h>

#include "server/common/access_control.h"
#include "server/scheduler/front_door.h"
#include "server/scheduler/http/dashboard_sessions.h"
#include "server/scheduler/http/host_allowlist.h"

namespace httplib {
class Server;
class Request;
class Response;
}  // namespace httplib

namespace farm {

struct DashboardOptions {
  std::string listen;                // HOST:PORT; port 0 picks a free one
  std::filesystem::path tls_cert;    // with tls_key: HTTPS
  std::filesystem::path tls_key;
  int max_event_streams = 32;        // open at once; more are answered 503
  // --http-host: names beyond the listen address, loopback and IP literals that requests may
  // carry in Host (host_allowlist.h); any other Host is answered 421.
  std::vector<std::string> host_names;
};

class DashboardServer {
 public:
  // Binds and starts serving on a thread of its own. InputError when the address cannot be bound.
  // Callers are authenticated with the front door's tokens (its access()).
  DashboardServer(SchedulerFrontDoor& front_door, DashboardOptions options, spdlog::logger& log);
  ~DashboardServer();  // stop()
  DashboardServer(const DashboardServer&) = delete;
  DashboardServer& operator=(const DashboardServer&) = delete;

  int port() const { return port_; }
  const std::string& scheme() const { return scheme_; }  // "http" or "https"
  // Stops accepting, ends the event streams, joins. Idempotent.
  void stop();

 private:
  void routes();
  // The caller of `request`: its bearer token, else its session, else (no tokens) anyone.
  Principal caller(const httplib::Request& request) const;
  // A POST that another site could have made a browser send: refused (ServiceError).
  void check_post(const httplib::Request& request) const;
  void serve_events(const httplib::Request& request, httplib::Response& response);
  void serve_file(const std::filesystem::path& file, const std::string& type, bool download,
                  httplib::Response& response) const;

  SchedulerFrontDoor& front_door_;
  const DashboardOptions options_;
  spdlog::logger& log_;
  DashboardSessions sessions_;
  std::unique_ptr<httplib::Server> server_;
  std::unique_ptr<HostAllowlist> hosts_;
  std::string scheme_ = "http";
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::atomic<int> streams_{0};
  std::thread thread_;
};

}  // namespace farm
