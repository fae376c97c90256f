#include "server/scheduler/dispatch/spot_check_rounds.h"

#include <fmt/format.h>

#include <algorithm>
#include <random>

#include "server/common/job_state.h"
#include "server/common/network_address.h"
#include "server/common/service_error.h"
#include "server/common/tile_codec.h"
#include "server/common/tile_result_check.h"

namespace farm {

namespace {

std::string describe(const UnitSpan& span) { return describe_units(span.first, span.count); }

// Pixels rendered in this process come as a buffer; a spot check compares encoded tiles.
void encode_pixels(RenderedTiles& result) {
  if (!result.pixels) return;
  encode_tile(*result.pixels, *result.response.mutable_tile());
  result.pixels.reset();
}

// The scheduler's secret for choosing which units are checked (spot_checks.h).
std::uint64_t random_key() {
  std::random_device device;
  return (static_cast<std::uint64_t>(device()) << 32) ^ device();
}

}  // namespace

SpotCheckRounds::SpotCheckRounds(const Parts& parts)
    : options_(parts.options),
      store_(parts.store),
      workers_(parts.workers),
      failures_(parts.failures),
      control_(parts.control),
      log_(parts.log),
      chooser_(parts.options.verify_fraction, random_key()),
      remote_chooser_(std::max(parts.options.verify_fraction, parts.options.remote_verify_fraction), random_key()) {}

bool SpotCheckRounds::holds_locked(const std::shared_ptr<SpotCheck>& check) const {
  return std::find(checks_.begin(), checks_.end(), check) != checks_.end();
}

const SpotCheckChooser& SpotCheckRounds::chooser_for(const WorkerEntry& w) const {
  // Spot checks by default for workers on other hosts (their replies crossed a network).
  return on_this_host(w.worker->describe()) ? chooser_ : remote_chooser_;
}

bool SpotCheckRounds::may_hold(const WorkerEntry& w) const { return chooser_for(w).enabled(); }

bool SpotCheckRounds::hold(const WorkerEntry& w, const UnitBatch& batch, const RenderSettings& settings,
                           RenderedTiles& result) {
  const std::string worker = w.worker->describe();
  const SpotCheckChooser& chooser = chooser_for(w);
  if (!chooser.enabled()) return false;
  std::optional<UnitSpan> span;
  if (const std::optional<v1::Job> job = store_.jobs().get_job(batch.job_id)) {
    span = chooser.span(batch, job->tiles_total(), UnitGrid(settings, options_.min_unit_edge));
  }
  // With no other worker to ask, there is nobody to check against: kept as it is.
  if (!span || !workers_.any_available_except({w.id})) return false;
  auto check = std::make_shared<SpotCheck>();
  check->batch = batch;
  check->span = *span;
  encode_pixels(result);
  check->opinions.push_back({w.id, worker, crop_tile(result.response.tile(), span->rect)});
  check->reply = std::move(result);
  check->asked.insert(w.id);
  bool stopped;
  {
    std::lock_guard lock(mutex_);
    stopped = stopped_;
    if (!stopped) checks_.push_back(check);
  }
  if (stopped) {
    store_.units().batch_requeue(batch.job_id, batch.first, batch.count, w.id);
    return true;
  }
  log_.debug("job {} {}: held for a spot check of {}", batch.job_id, describe(batch), describe(*span));
  settle_stranded();
  control_.wake();
  return true;
}

std::shared_ptr<SpotCheck> SpotCheckRounds::next_for(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  for (const std::shared_ptr<SpotCheck>& c : checks_) {
    if (!c->queued || c->asked.contains(worker_id)) continue;
    c->queued = false;
    c->asked.insert(worker_id);
    return c;
  }
  return nullptr;
}

void SpotCheckRounds::put_back(const std::shared_ptr<SpotCheck>& check) {
  std::lock_guard lock(mutex_);
  check->queued = true;
}

void SpotCheckRounds::on_reply(WorkerEntry& w, const std::shared_ptr<SpotCheck>& check, const grpc::Status& status,
                               CancelReason reason, RenderedTiles& result) {
  if (reason == CancelReason::JobCancelled || reason == CancelReason::Stopping) return;  // dropped already
  const std::string worker = w.worker->describe();
  const UnitBatch& batch = check->batch;
  std::string problem;
  const bool answered = status.ok() && reason != CancelReason::Quarantined;
  if (answered && !result.pixels) {
    const std::optional<RenderSettings> settings = control_.settings_of(batch);
    if (!settings) return;
    problem = check_tile_reply(result.response, *settings, check->span.rect);
  }
  if (!answered || !problem.empty()) {
    // No opinion from this worker: the check waits for another.
    if (!problem.empty()) {
      control_.quarantine(w.id, worker, fmt::format("worker {} sent a result no engine makes: {}", worker, problem));
    } else if (reason == CancelReason::None) {
      log_.warn("job {} {}: checking it on worker {} failed: {}: {}", batch.job_id, describe(check->span), worker,
                status_code_name(status.error_code()), status.error_message());
      if (status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) workers_.mark_down(w, std::chrono::milliseconds(0));
      if (status.error_code() == grpc::StatusCode::UNAVAILABLE) workers_.mark_down(w, options_.probe_interval);
    }
    put_back(check);
    settle_stranded();
    control_.wake();
    return;
  }
  encode_pixels(result);
  Opinion opinion{w.id, worker, std::move(*result.response.mutable_tile())};
  Judgement j;
  std::string own_worker;
  {
    std::lock_guard lock(mutex_);
    if (!holds_locked(check)) return;  // its batch's worker was quarantined, or its job ended
    j = judge(check->opinions, opinion);
    own_worker = check->own().worker;
    if (j.outcome == Judgement::Outcome::NeedAnother) {
      check->queued = true;  // back in the queue: from here on others may touch it
    } else {
      checks_.remove(check);  // out of checks_, it is this thread's alone
    }
  }
  switch (j.outcome) {
    case Judgement::Outcome::NeedAnother:
      log_.warn("job {} {}: workers {} and {} rendered it differently; a third worker decides", batch.job_id,
                describe(check->span), own_worker, worker);
      settle_stranded();
      control_.wake();
      return;
    case Judgement::Outcome::NoAgreement: {
      std::string names;
      for (const Opinion& o : check->opinions) names += (names.empty() ? "" : ", ") + o.worker;
      failures_.fail(check->own().worker_id, check->own().worker, batch,
                     fmt::format("spot check of {}: workers {} rendered it three different ways",
                                 describe(check->span), names),
                     options_.max_attempts);
      return;
    }
    case Judgement::Outcome::Agreed:
      settle(*check, j, opinion);
      return;
  }
}

void SpotCheckRounds::settle(SpotCheck& check, const Judgement& j, const Opinion& agreeing) {
  const UnitBatch& batch = check.batch;
  const Opinion& agreed = check.opinions[j.agreed_with];
  if (j.agreed_with == 0) {
    log_.debug("job {} {}: spot check passed ({} and {} agree)", batch.job_id, describe(check.span), agreed.worker,
               agreeing.worker);
    control_.keep(check.own().worker_id, check.own().worker, batch, check.reply);
  }
  for (std::size_t k : j.wrong) {
    const Opinion& o = check.opinions[k];
    const std::string why =
        fmt::format("spot check of {} of job {}: its pixels differ from the ones workers {} and {} rendered",
                    describe(check.span), batch.job_id, agreed.worker, agreeing.worker);
    if (k == 0) {
      // The batch's own worker: the batch is rendered again.
      failures_.fail(o.worker_id, o.worker, batch, fmt::format("worker {}: {}; the worker is quarantined", o.worker, why),
                     options_.max_attempts);
    } else {
      const std::string kept =
          fmt::format("worker {}: {}; the worker is quarantined, the tiles are kept as {} rendered them", o.worker,
                      why, check.own().worker);
      log_.warn("job {} {}: {}", batch.job_id, describe(check.span), kept);
      failures_.announce(batch.job_id, check.span.first, check.span.count, o.worker, kept, false);
    }
    control_.quarantine(o.worker_id, o.worker, fmt::format("worker {}: {}", o.worker, why));
  }
}

void SpotCheckRounds::settle_stranded() {
  std::vector<std::shared_ptr<SpotCheck>> stranded;
  {
    std::lock_guard lock(mutex_);
    for (auto it = checks_.begin(); it != checks_.end();) {
      if ((*it)->queued && !workers_.any_available_except((*it)->asked)) {
        stranded.push_back(*it);
        it = checks_.erase(it);
      } else {
        ++it;
      }
    }
  }
  for (const std::shared_ptr<SpotCheck>& c : stranded) {
    if (c->opinions.size() == 1) {
      log_.warn("job {} {}: kept unchecked: no worker but {} is there to check it on", c->batch.job_id,
                describe(c->batch), c->own().worker);
      control_.keep(c->own().worker_id, c->own().worker, c->batch, c->reply);
    } else {
      std::string names;
      for (const Opinion& o : c->opinions) names += (names.empty() ? "" : " and ") + o.worker;
      failures_.fail(c->own().worker_id, c->own().worker, c->batch,
                     fmt::format("spot check of {}: workers {} rendered it differently and no other worker is there "
                                 "to decide",
                                 describe(c->span), names),
                     options_.max_attempts);
    }
  }
}

void SpotCheckRounds::drop_job(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  checks_.remove_if([&](const std::shared_ptr<SpotCheck>& c) { return c->batch.job_id == job_id; });
}

void SpotCheckRounds::drop_worker(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  for (auto it = checks_.begin(); it != checks_.end();) {
    SpotCheck& c = **it;
    if (c.own().worker_id == worker_id) {
      it = checks_.erase(it);  // its batch: the store takes the units back (quarantine_worker)
      continue;
    }
    std::erase_if(c.opinions, [&](const Opinion& o) { return o.worker_id == worker_id; });
    ++it;
  }
}

std::vector<std::shared_ptr<SpotCheck>> SpotCheckRounds::stop() {
  std::lock_guard lock(mutex_);
  stopped_ = true;
  std::vector<std::shared_ptr<SpotCheck>> held(checks_.begin(), checks_.end());
  checks_.clear();
  return held;
}

}  // namespace farm
