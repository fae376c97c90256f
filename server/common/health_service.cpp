#include "server/common/health_service.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>
#include <utility>

namespace farm {

// One Watch call. gRPC allows one write in flight per call, so a status that changes while a
// write is under way goes out when that write completes (only the newest: a watcher wants the
// status now, not its history). The call ends once nothing is in flight and it has a reason to:
// the client went, or the server is shutting down (after its NOT_SERVING has been written).
class HealthService::Watcher final : public grpc::ServerWriteReactor<Response> {
 public:
  Watcher(HealthService& health, std::string service_name)
      : service(std::move(service_name)), health_(health) {}

  void OnWriteDone(bool ok) override { health_.write_done(*this, ok); }
  void OnCancel() override { health_.cancelled(*this); }
  void OnDone() override {
    health_.done(*this);
    delete this;
  }

  // The state below belongs to HealthService, which reads and writes it with its mutex held.
  const std::string service;
  bool writing = false;      // `message` is being written
  bool client_gone = false;  // cancelled, or a write failed: nothing more can be written
  bool finished = false;     // Finish has been called
  std::optional<Response::ServingStatus> sent;  // the status last written
  std::optional<grpc::Status> end_with;  // end the call with this once nothing is in flight
  Response message;

 private:
  HealthService& health_;
};

namespace {

// How a Watch ends when the server stops: clients retry on anything but UNIMPLEMENTED, and this
// says why they have to.
grpc::Status shutting_down() {
  return grpc::Status(grpc::StatusCode::UNAVAILABLE, "the server is shutting down");
}

}  // namespace

HealthService::HealthService(std::vector<std::string> services) : services_(std::move(services)) {}

HealthService::Response::ServingStatus HealthService::status_of(
    const std::string& service) const {
  const bool known =
      service.empty() || std::find(services_.begin(), services_.end(), service) != services_.end();
  if (!known) return Response::SERVICE_UNKNOWN;
  return shut_down_ ? Response::NOT_SERVING : Response::SERVING;
}

grpc::ServerUnaryReactor* HealthService::Check(grpc::CallbackServerContext* context,
                                               const Request* request, Response* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  std::unique_lock lock(mutex_);
  const Response::ServingStatus status = status_of(request->service());
  lock.unlock();
  if (status == Response::SERVICE_UNKNOWN) {
    std::string known = "\"\"";
    for (const std::string& s : services_) known += ", " + s;
    reactor->Finish(grpc::Status(grpc::StatusCode::NOT_FOUND,
                                 fmt::format("unknown service '{}': this server answers for {}",
                                             request->service(), known)));
  } else {
    response->set_status(status);
    reactor->Finish(grpc::Status::OK);
  }
  return reactor;
}

grpc::ServerWriteReactor<HealthService::Response>* HealthService::Watch(
    grpc::CallbackServerContext* /*context*/, const Request* request) {
  auto* watcher = new Watcher(*this, request->service());
  std::unique_lock lock(mutex_);
  watchers_.insert(watcher);
  if (shut_down_) watcher->end_with = shutting_down();
  const Step step = next_step(*watcher);
  lock.unlock();
  take(*watcher, step);
  return watcher;
}

void HealthService::shutdown() {
  std::vector<std::pair<Watcher*, Step>> steps;
  {
    std::lock_guard lock(mutex_);
    shut_down_ = true;
    for (Watcher* watcher : watchers_) {
      if (!watcher->end_with) watcher->end_with = shutting_down();
      const Step step = next_step(*watcher);
      // One with nothing to do may be finished already, and gone as soon as the lock is released.
      if (step != Step::None) steps.emplace_back(watcher, step);
    }
  }
  // Each step was decided under the lock and is the only one its watcher can take until the
  // operation it starts completes, so taking them unlocked races with nothing.
  for (const auto& [watcher, step] : steps) take(*watcher, step);
}

HealthService::Step HealthService::next_step(Watcher& watcher) {
  if (watcher.finished || watcher.writing) return Step::None;
  if (!watcher.client_gone) {
    const Response::ServingStatus now = status_of(watcher.service);
    if (watcher.sent != now) {
      watcher.sent = now;
      watcher.message.set_status(now);
      watcher.writing = true;
      return Step::Write;
    }
  }
  if (watcher.end_with) {
    watcher.finished = true;
    return Step::Finish;
  }
  return Step::None;
}

void HealthService::take(Watcher& watcher, Step step) {
  switch (step) {
    case Step::None:
      break;
    case Step::Write:
      watcher.StartWrite(&watcher.message);
      break;
    case Step::Finish:
      // `end_with` is not touched again once `finished` is set, and the call (with the watcher)
      // may be gone as soon as Finish returns.
      watcher.Finish(*watcher.end_with);
      break;
  }
}

void HealthService::write_done(Watcher& watcher, bool ok) {
  std::unique_lock lock(mutex_);
  watcher.writing = false;
  if (!ok) {
    watcher.client_gone = true;
    if (!watcher.end_with) watcher.end_with = grpc::Status::CANCELLED;
  }
  const Step step = next_step(watcher);
  lock.unlock();
  take(watcher, step);
}

void HealthService::cancelled(Watcher& watcher) {
  std::unique_lock lock(mutex_);
  watcher.client_gone = true;
  if (!watcher.end_with) watcher.end_with = grpc::Status::CANCELLED;
  const Step step = next_step(watcher);
  lock.unlock();
  take(watcher, step);
}

void HealthService::done(Watcher& watcher) {
  std::lock_guard lock(mutex_);
  watchers_.erase(&watcher);
}

}  // namespace farm
