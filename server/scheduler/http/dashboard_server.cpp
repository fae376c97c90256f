#include "server/scheduler/http/dashboard_server.h"

#include <fmt/format.h>
#include <google/protobuf/struct.pb.h>
#include <httplib.h>

#include <nlohmann/json.hpp>

#include <charconv>
#include <fstream>
#include <memory>
#include <vector>

#include "renderer/util/input_error.h"
#include "server/common/job_state.h"
#include "server/common/hex.h"
#include "server/common/plain_file_name.h"
#include "server/common/proto_json.h"
#include "server/common/service_error.h"
#include "server/scheduler/http/prometheus_text.h"
#include "server/scheduler/http/web_assets.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr const char* kSessionCookie = "farm_session";
constexpr std::size_t kMaxBody = 64 * 1024;
constexpr std::size_t kEventQueue = 4096;  // events a slow reader may fall behind by
constexpr auto kEventWait = std::chrono::seconds(1);
constexpr std::size_t kFileChunk = 1 << 20;
// A whole job id as the routes take it (the pages hold whole ids): lowercase hex, 1 to 64 digits.
constexpr const char* kJobRoute = "/api/v1/jobs/([0-9a-f]{1,64})";

int http_status(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::INVALID_ARGUMENT: return 400;
    case grpc::StatusCode::UNAUTHENTICATED: return 401;
    case grpc::StatusCode::PERMISSION_DENIED: return 403;
    case grpc::StatusCode::NOT_FOUND: return 404;
    case grpc::StatusCode::FAILED_PRECONDITION: return 409;
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return 429;
    case grpc::StatusCode::UNAVAILABLE: return 503;
    default: return 500;
  }
}

// A JSON string of `text` (the small replies written here, not from a message).
std::string json_string(std::string_view text) {
  return nlohmann::json(std::string(text)).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

void reply_json(httplib::Response& response, const std::string& json, int status = 200) {
  response.status = status;
  response.set_header("Cache-Control", "no-store");
  response.set_content(json, "application/json");
}

void reply_message(httplib::Response& response, const google::protobuf::Message& message) {
  reply_json(response, json_of(message));
}

// What a page or call is allowed to do in the browser: nothing from elsewhere.
void secure_headers(httplib::Response& response) {
  response.set_header("Content-Security-Policy",
                      "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; "
                      "frame-ancestors 'none'");
  response.set_header("X-Content-Type-Options", "nosniff");
  response.set_header("X-Frame-Options", "DENY");
  response.set_header("Referrer-Policy", "no-referrer");
}

// A handler whose exceptions become JSON errors with the status the RPC would have had.
template <typename F>
httplib::Server::Handler guarded(F body) {
  return [body = std::move(body)](const httplib::Request& request, httplib::Response& response) {
    secure_headers(response);
    try {
      body(request, response);
    } catch (...) {
      const grpc::Status status = status_of_current_exception();
      reply_json(response,
                 fmt::format("{{\"error\": {}, \"message\": {}}}", json_string(status_code_name(status.error_code())),
                             json_string(status.error_message())),
                 http_status(status.error_code()));
    }
  };
}

std::string cookie_value(const httplib::Request& request, std::string_view name) {
  const std::string cookies = request.get_header_value("Cookie");
  std::string_view rest = cookies;
  while (!rest.empty()) {
    const std::size_t end = rest.find(';');
    std::string_view item = rest.substr(0, end);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    if (item.size() > name.size() && item.substr(0, name.size()) == name && item[name.size()] == '=') {
      return std::string(item.substr(name.size() + 1));
    }
    if (end == std::string_view::npos) break;
    rest.remove_prefix(end + 1);
  }
  return {};
}

int int_param(const httplib::Request& request, const char* name, int fallback) {
  if (!request.has_param(name)) return fallback;
  const std::string text = request.get_param_value(name);
  int value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) {
    throw InputError(fmt::format("{}={}: not a whole number", name, text.substr(0, 20)));
  }
  return value;
}

std::vector<v1::JobState> states_param(const std::string& text) {
  std::vector<v1::JobState> states;
  std::string_view rest = text;
  while (!rest.empty()) {
    const std::size_t comma = rest.find(',');
    const std::string name(rest.substr(0, comma));
    const std::optional<v1::JobState> state = job_state_named(name);
    if (!state) throw InputError(fmt::format("state={}: not a job state", name.substr(0, 20)));
    states.push_back(*state);
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return states;
}

v1::ResultKind kind_param(const std::string& text) {
  if (text == "exr") return v1::RESULT_KIND_EXR;
  if (text == "preview") return v1::RESULT_KIND_PREVIEW;
  if (text == "video") return v1::RESULT_KIND_VIDEO;
  if (text == "progressive") return v1::RESULT_KIND_PROGRESSIVE;
  throw InputError(fmt::format("kind={}: one of exr, preview, video, progressive", text.substr(0, 20)));
}

std::string content_type_of(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".png") return "image/png";
  if (ext == ".exr") return "image/x-exr";
  if (ext == ".mp4") return "video/mp4";
  if (ext == ".webm") return "video/webm";
  return "application/octet-stream";
}

// A file's name as a download header may carry it: the stem is the submitter's output name.
std::string download_name(const fs::path& file) { return plain_file_name(file.filename().string(), "download"); }

}  // namespace

DashboardServer::DashboardServer(SchedulerFrontDoor& front_door, DashboardOptions options, spdlog::logger& log)
    : front_door_(front_door), options_(std::move(options)), log_(log) {
  if (!options_.tls_cert.empty()) {
    auto ssl = std::make_unique<httplib::SSLServer>(options_.tls_cert.c_str(), options_.tls_key.c_str());
    if (!ssl->is_valid()) {
      throw InputError(fmt::format("--http: cannot serve HTTPS with {} and {}", options_.tls_cert.string(),
                                   options_.tls_key.string()));
    }
    server_ = std::move(ssl);
    scheme_ = "https";
  } else {
    server_ = std::make_unique<httplib::Server>();
  }
  // Event streams hold a thread each while they last: the pool has room for them and for calls.
  const int threads = options_.max_event_streams + 8;
  server_->new_task_queue = [threads] { return new httplib::ThreadPool(static_cast<std::size_t>(threads)); };
  server_->set_payload_max_length(kMaxBody);
  // An idle or slow connection holds a thread of the pool, and stop() waits for it: bounded.
  server_->set_keep_alive_timeout(1);
  server_->set_read_timeout(2, 0);
  const std::size_t colon = options_.listen.rfind(':');
  if (colon == std::string::npos) throw InputError(fmt::format("--http '{}': give HOST:PORT", options_.listen));
  std::string host = options_.listen.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  hosts_ = std::make_unique<HostAllowlist>(host, options_.host_names);
  // Before any route: a request for another name (DNS rebinding) reaches no page and no call.
  server_->set_pre_routing_handler([this](const httplib::Request& request, httplib::Response& response) {
    const std::string name = request.get_header_value("Host");
    if (hosts_->allows(name)) return httplib::Server::HandlerResponse::Unhandled;
    secure_headers(response);
    reply_json(response,
               fmt::format("{{\"error\": \"MISDIRECTED\", \"message\": {}}}",
                           json_string(fmt::format("this dashboard does not answer to Host '{}': it answers to {} "
                                                   "(farm scheduler --http-host NAME adds a name)",
                                                   name.substr(0, 100), hosts_->describe()))),
               421);
    return httplib::Server::HandlerResponse::Handled;
  });
  routes();
  int port = 0;
  const std::string port_text = options_.listen.substr(colon + 1);
  const auto [end, error] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (error != std::errc() || end != port_text.data() + port_text.size() || port < 0 || port > 65535) {
    throw InputError(fmt::format("--http '{}': the port is not a number from 0 to 65535", options_.listen));
  }
  port_ = port == 0 ? server_->bind_to_any_port(host) : (server_->bind_to_port(host, port) ? port : -1);
  if (port_ <= 0) throw InputError(fmt::format("--http: cannot listen on '{}'", options_.listen));
  thread_ = std::thread([this] { server_->listen_after_bind(); });
}

DashboardServer::~DashboardServer() { stop(); }

void DashboardServer::stop() {
  stopping_ = true;  // the event streams end within kEventWait
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

Principal DashboardServer::caller(const httplib::Request& request) const {
  const std::string authorization = request.get_header_value("Authorization");
  if (!authorization.empty()) {
    constexpr std::string_view kBearer = "Bearer ";
    if (authorization.size() <= kBearer.size() || authorization.compare(0, kBearer.size(), kBearer) != 0) {
      throw ServiceError(grpc::StatusCode::UNAUTHENTICATED, "Authorization: give 'Bearer <token>'");
    }
    return front_door_.access().authenticate_token(std::string_view(authorization).substr(kBearer.size()));
  }
  if (!front_door_.access().requires_tokens()) return front_door_.access().authenticate_token({});
  const std::string session = cookie_value(request, kSessionCookie);
  if (!session.empty()) {
    if (std::optional<Principal> who = sessions_.find(session)) return std::move(*who);
  }
  throw ServiceError(grpc::StatusCode::UNAUTHENTICATED, "log in with a token (this scheduler asks for tokens)");
}

void DashboardServer::check_post(const httplib::Request& request) const {
  // A page elsewhere can make a browser send a form or a "simple" request here, with its cookies;
  // it cannot send application/json without the CORS preflight this server never answers.
  const std::string type = request.get_header_value("Content-Type");
  if (type.rfind("application/json", 0) != 0) {
    throw ServiceError(grpc::StatusCode::PERMISSION_DENIED, "a POST must be Content-Type: application/json");
  }
  const std::string origin = request.get_header_value("Origin");
  if (!origin.empty() && origin != scheme_ + "://" + request.get_header_value("Host")) {
    throw ServiceError(grpc::StatusCode::PERMISSION_DENIED,
                       fmt::format("a POST from '{}': only this dashboard's own pages may act", origin.substr(0, 100)));
  }
}

void DashboardServer::serve_file(const fs::path& file, const std::string& type, bool download,
                                 httplib::Response& response) const {
  // The size is the open file's: a live image is replaced (renamed over) while it is served.
  auto in = std::make_shared<std::ifstream>(file, std::ios::binary | std::ios::ate);
  if (!*in) throw ServiceError(grpc::StatusCode::NOT_FOUND, fmt::format("{} is gone", download_name(file)));
  const std::streamoff size = in->tellg();
  if (size < 0) throw ServiceError(grpc::StatusCode::NOT_FOUND, fmt::format("cannot read {}", download_name(file)));
  response.set_header("Cache-Control", "no-store");
  if (download) {
    response.set_header("Content-Disposition", fmt::format("attachment; filename=\"{}\"", download_name(file)));
  }
  response.set_content_provider(static_cast<std::size_t>(size), type,
                                [in](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                                  std::string buffer(std::min(length, kFileChunk), '\0');
                                  in->seekg(static_cast<std::streamoff>(offset));
                                  in->read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
                                  const auto n = static_cast<std::size_t>(in->gcount());
                                  return n > 0 && sink.write(buffer.data(), n);
                                });
}

void DashboardServer::serve_events(const httplib::Request& request, httplib::Response& response) {
  const Principal who = caller(request);
  const std::string job = request.has_param("job") ? request.get_param_value("job") : std::string();
  // Held by the stream's callback: unsubscribed once the response that holds it is gone.
  const std::shared_ptr<JobWatch> watch =
      job.empty() ? front_door_.watch_every_job(who, kEventQueue) : front_door_.watch_job(who, job, kEventQueue);
  if (++streams_ > options_.max_event_streams) {
    --streams_;
    throw ServiceError(grpc::StatusCode::UNAVAILABLE, "too many event streams open: try again later");
  }
  response.set_header("Cache-Control", "no-store");
  response.set_header("X-Accel-Buffering", "no");
  auto number = std::make_shared<std::uint64_t>(0);
  response.set_chunked_content_provider(
      "text/event-stream",
      [this, watch, number](std::size_t, httplib::DataSink& sink) {
        if (stopping_) return false;
        std::string out;
        if (watch->dropped()) out += "event: resync\ndata: {}\n\n";  // the page reloads the jobs
        v1::JobEvent event;
        bool heard = false;
        try {
          heard = watch->next(event, kEventWait);
        } catch (const std::exception&) {
          return false;  // the job could not be read again: the stream ends, the page reconnects
        }
        if (heard) {
          out += fmt::format("id: {}\nevent: job\ndata: {}\n\n", ++*number, json_of(event));
        } else {
          out += ": still here\n\n";  // finds a reader that went away
        }
        return sink.write(out.data(), out.size());
      },
      [this](bool) { --streams_; });
}

void DashboardServer::routes() {
  httplib::Server& s = *server_;

  // ---- The pages ---------------------------------------------------------------------------------
  s.Get("/((?:[a-z_]+\\.(?:html|js|css|svg))?)", [](const httplib::Request& request, httplib::Response& response) {
    secure_headers(response);
    const std::string name = request.matches[1].str().empty() ? "index.html" : request.matches[1].str();
    const WebAsset* asset = find_web_asset(name);
    if (!asset) {
      response.status = 404;
      response.set_content("no such page", "text/plain");
      return;
    }
    response.set_header("Cache-Control", "no-cache");
    response.set_content(std::string(asset->bytes), std::string(asset->type));
  });

  // ---- Who is calling ----------------------------------------------------------------------------
  s.Get("/api/v1/whoami", guarded([this](const httplib::Request& request, httplib::Response& response) {
    const Principal who = caller(request);
    reply_json(response, fmt::format("{{\"name\": {}, \"roles\": {}, \"tokens_required\": {}}}", json_string(who.name),
                                     json_string(to_string(who.roles)), front_door_.access().requires_tokens()));
  }));
  s.Post("/api/v1/login", guarded([this](const httplib::Request& request, httplib::Response& response) {
    check_post(request);
    std::string token;
    {
      // The body is one small JSON object; a field we do not know is an error, as everywhere.
      google::protobuf::Struct body;
      parse_json(request.body, body, "login");
      const auto it = body.fields().find("token");
      if (it == body.fields().end() || body.fields().size() != 1 || !it->second.has_string_value()) {
        throw InputError("login: give {\"token\": \"...\"}");
      }
      token = it->second.string_value();
    }
    if (!front_door_.access().requires_tokens()) throw InputError("login: this scheduler asks for no tokens");
    const Principal who = front_door_.access().authenticate_token(token);
    const std::string session = sessions_.open(who);
    response.set_header("Set-Cookie", fmt::format("{}={}; Path=/; HttpOnly; SameSite=Strict; Max-Age={}{}",
                                                  kSessionCookie, session,
                                                  std::chrono::duration_cast<std::chrono::seconds>(
                                                      DashboardSessions::kLifetime)
                                                      .count(),
                                                  scheme_ == "https" ? "; Secure" : ""));
    log_.info("dashboard: '{}' logged in", who.name);
    reply_json(response, fmt::format("{{\"name\": {}, \"roles\": {}}}", json_string(who.name),
                                     json_string(to_string(who.roles))));
  }));
  s.Post("/api/v1/logout", guarded([this](const httplib::Request& request, httplib::Response& response) {
    check_post(request);
    sessions_.close(cookie_value(request, kSessionCookie));
    response.set_header("Set-Cookie", fmt::format("{}=; Path=/; HttpOnly; SameSite=Strict; Max-Age=0", kSessionCookie));
    reply_json(response, "{}");
  }));

  // ---- Jobs --------------------------------------------------------------------------------------
  s.Get("/api/v1/jobs", guarded([this](const httplib::Request& request, httplib::Response& response) {
    v1::ListJobsRequest list;
    if (request.has_param("state")) {
      for (v1::JobState state : states_param(request.get_param_value("state"))) list.add_states(state);
    }
    list.set_name(request.get_param_value("name"));
    list.set_id_prefix(request.get_param_value("id_prefix"));
    list.set_page_size(int_param(request, "page_size", 0));
    list.set_page_token(request.get_param_value("page_token"));
    reply_message(response, front_door_.list_jobs(caller(request), list));
  }));
  s.Get(kJobRoute, guarded([this](const httplib::Request& request, httplib::Response& response) {
    reply_message(response, front_door_.get_job(caller(request), request.matches[1]));
  }));
  s.Get(std::string(kJobRoute) + "/log", guarded([this](const httplib::Request& request, httplib::Response& response) {
    v1::GetJobLogRequest log;
    log.set_job_id(request.matches[1]);
    log.set_after(static_cast<std::uint32_t>(std::max(0, int_param(request, "after", 0))));
    reply_message(response, front_door_.job_log(caller(request), log));
  }));
  s.Post(std::string(kJobRoute) + "/(cancel|pause|resume|retry|delete|priority|limits|dependencies)",
         guarded([this](const httplib::Request& request, httplib::Response& response) {
           check_post(request);
           const Principal who = caller(request);
           const std::string id = request.matches[1], action = request.matches[2];
           if (action == "cancel") {
             reply_message(response, front_door_.cancel_job(who, id));
           } else if (action == "pause" || action == "resume") {
             reply_message(response, front_door_.pause_job(who, id, action == "pause"));
           } else if (action == "retry") {
             reply_message(response, front_door_.retry_job(who, id));
           } else if (action == "delete") {
             reply_message(response, front_door_.delete_job(who, id));
           } else if (action == "limits") {
             v1::SetJobLimitsRequest limits;
             parse_json(request.body, limits, "limits");
             limits.set_job_id(id);
             reply_message(response, front_door_.set_job_limits(who, limits));
           } else if (action == "dependencies") {
             v1::AddDependenciesRequest dependencies;
             parse_json(request.body, dependencies, "dependencies");
             dependencies.set_job_id(id);
             reply_message(response, front_door_.add_dependencies(who, dependencies));
           } else {
             v1::SetPriorityRequest priority;
             parse_json(request.body, priority, "priority");
             reply_message(response, front_door_.set_priority(who, id, priority.priority()));
           }
         }));
  s.Get(std::string(kJobRoute) + "/live", guarded([this](const httplib::Request& request, httplib::Response& response) {
    std::optional<int> frame;
    if (request.has_param("frame")) frame = int_param(request, "frame", 0);
    serve_file(front_door_.live_preview(caller(request), request.matches[1], frame), "image/png", false, response);
  }));
  s.Get(std::string(kJobRoute) + "/file", guarded([this](const httplib::Request& request, httplib::Response& response) {
    v1::GetResultRequest result;
    result.set_job_id(request.matches[1]);
    result.set_kind(kind_param(request.get_param_value("kind")));
    if (request.has_param("frame")) result.set_frame(int_param(request, "frame", 0));
    const fs::path file = front_door_.result_file(caller(request), result);
    serve_file(file, content_type_of(file), result.kind() != v1::RESULT_KIND_PREVIEW &&
                                                result.kind() != v1::RESULT_KIND_PROGRESSIVE, response);
  }));

  // ---- Workers, events, metrics ------------------------------------------------------------------
  s.Get("/api/v1/workers", guarded([this](const httplib::Request& request, httplib::Response& response) {
    reply_message(response, front_door_.list_workers(caller(request)));
  }));
  s.Get("/api/v1/events", guarded([this](const httplib::Request& request, httplib::Response& response) {
    serve_events(request, response);
  }));
  s.Get("/metrics", guarded([this](const httplib::Request& request, httplib::Response& response) {
    const SchedulerMetrics metrics = front_door_.metrics(caller(request));
    response.set_header("Cache-Control", "no-store");
    response.set_content(prometheus_text(metrics), "text/plain; version=0.0.4");
  }));
}

}  // namespace farm
