#include "server/cli/job_display.h"
#include "server/common/job_eta.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstdio>
#include <ctime>

#include "server/cli/progress_bar.h"
#include "server/common/job_state.h"

namespace farm {

std::string frames_of(const v1::Job& job) {
  if (job.frames_total() <= 1 && job.frame_first() == 0) return {};  // a still
  return fmt::format("{}/{} frames", job.frames_done(), job.frames_total());
}

std::string progress_of(const v1::Job& job) {
  const std::string frames = frames_of(job);
  // The one word for the scheduler's piece of work (a tile of a frame's sample pass) in every
  // message: a unit (issue #32: submit said tiles, status units, log tiles, for the same things).
  return fmt::format("{}{}/{} units", frames.empty() ? "" : frames + ", ", job.tiles_done(), job.tiles_total());
}

std::string local_time(const google::protobuf::Timestamp& t) {
  if (t.seconds() == 0) return "-";
  const std::time_t seconds = static_cast<std::time_t>(t.seconds());
  std::tm tm{};
  localtime_r(&seconds, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S", &tm);
  return text;
}

std::string state_label(const v1::Job& job) {
  return job.paused() && !is_final(job.state()) ? "paused" : to_string(job.state());
}

std::string describe_event(const v1::JobEvent& event) {
  const v1::Job& job = event.job();
  switch (event.event_case()) {
    case v1::JobEvent::kSnapshot:
      return fmt::format("{} ({})", state_label(job), progress_of(job));
    case v1::JobEvent::kStateChanged: {
      const v1::JobStateChanged& c = event.state_changed();
      if (c.from() == v1::JOB_STATE_UNSPECIFIED) {
        return fmt::format("submitted: {}, {} {}", to_string(c.to()), job.tiles_total(),
                           job.tiles_total() == 1 ? "unit" : "units");
      }
      return fmt::format("{} -> {} ({}){}{}", to_string(c.from()), to_string(c.to()), progress_of(job),
                         c.by().empty() ? "" : " by " + c.by(),
                         c.to() == v1::JOB_STATE_FAILED && !job.failure_reason().empty() ? ": " + job.failure_reason()
                                                                                          : "");
    }
    case v1::JobEvent::kTileFinished: {
      const v1::TileFinished& f = event.tile_finished();
      return fmt::format("{} of frame {} done on {}", describe_units(f.tile_index(), std::max(1u, f.tile_count())),
                         f.frame(), f.worker());
    }
    case v1::JobEvent::kTileFailed: {
      const v1::TileFailed& f = event.tile_failed();
      return fmt::format("{} failed on {}: {}{}", describe_units(f.tile_index(), std::max(1u, f.tile_count())),
                         f.worker().empty() ? "the scheduler" : f.worker(), f.reason(),
                         f.will_retry() ? " (will retry)" : "");
    }
    case v1::JobEvent::kFrameFinished:
      return fmt::format("frame {} merged ({})", event.frame_finished().frame(), progress_of(job));
    case v1::JobEvent::kPassFinished: {
      const v1::PassFinished& p = event.pass_finished();
      return fmt::format("frame {}: sample pass {}/{} done", p.frame(), p.pass() + 1, p.passes());
    }
    case v1::JobEvent::kUpdated:
      return fmt::format("{}{}", event.updated().change(),
                         event.updated().by().empty() ? "" : " (by " + event.updated().by() + ")");
    case v1::JobEvent::EVENT_NOT_SET:
      break;
  }
  return "an event this client does not know";
}

void print_log_entry(const v1::JobLogEntry& entry) {
  fmt::print("{}.{:03}  {}\n", local_time(entry.at()), entry.at().nanos() / 1000000, describe_event(entry.event()));
}

void print_job(const v1::Job& job) {
  fmt::print("job {} '{}': {}, {}\n", job.job_id(), job.name(), state_label(job), progress_of(job));
  fmt::print("  {} engine, {}x{}, scene {}\n", job.engine(), job.width(), job.height(),
             job.scene_hash().substr(0, 16));
  if (job.passes() > 1) {
    fmt::print("  {} sample passes a frame: a unit is a tile of one pass\n", job.passes());
  }
  if (!frames_of(job).empty()) {
    fmt::print("  frames {} to {} by {}: {} of {} merged\n", job.frame_first(), job.frame_last(), job.frame_step(),
               job.frames_done(), job.frames_total());
  }
  fmt::print("  submitted {}{}, started {}, finished {}\n", local_time(job.submitted_at()),
             job.owner().empty() ? "" : " by " + job.owner(), local_time(job.started_at()),
             local_time(job.finished_at()));
  if (const WorkerRequirements needs = requirements_of(job); !needs.empty()) {
    fmt::print("  runs on workers with {}\n", needs.describe());
  }
  if (!job.unplaceable().empty()) fmt::print("  waiting: {}\n", job.unplaceable());
  if (const std::string waits = describe_dependencies(job); !waits.empty()) {
    fmt::print("  {}: {}\n", job.state() == v1::JOB_STATE_WAITING ? "waiting" : "dependencies", waits);
  }
  if (job.dependents_size() > 0) fmt::print("  waited for by: {}\n", fmt::join(job.dependents(), ", "));
  if (job.max_workers() > 0 || job.max_units_in_flight() > 0) {
    fmt::print("  caps: {} workers, {} units in flight at once\n",
               job.max_workers() > 0 ? std::to_string(job.max_workers()) : "any",
               job.max_units_in_flight() > 0 ? std::to_string(job.max_units_in_flight()) : "any");
  }
  if (job.tile_failures() > 0) fmt::print("  unit retries: {}\n", job.tile_failures());
  if (!job.failure_reason().empty()) fmt::print("  failure: {}\n", job.failure_reason());
  const v1::TileStats& s = job.stats();
  if (s.samples() > 0) fmt::print("  samples: {} traced, {} NaN/inf dropped\n", s.samples(), s.invalid_samples());
  if (s.rays() > 0) fmt::print("  rays: {}\n", s.rays());
  if (s.render_ms() > 0) fmt::print("  render time summed over tiles: {:.1f} ms\n", s.render_ms());
  if (s.cpu_ms() > 0) fmt::print("  CPU time of the render threads: {:.1f} ms\n", s.cpu_ms());
  if (job.render_seconds() > 0) {
    fmt::print("  wall time from the first tile handed out to the merged image: {:.3f} s\n", job.render_seconds());
  }
}

v1::Job follow(SchedulerClient& client, const std::string& job_id,
               const std::function<void(const v1::JobEvent&)>& also) {
  const bool terminal = ProgressBar::stderr_is_terminal();
  ProgressBar bar(fmt::format("job {}", job_id), terminal);
  v1::JobState shown = v1::JOB_STATE_UNSPECIFIED;
  const v1::Job last = client.watch(job_id, [&](const v1::JobEvent& event) {
    const v1::Job& job = event.job();
    const std::optional<std::chrono::seconds> eta = job_eta(job, std::chrono::system_clock::now());
    const std::string eta_text = eta ? "ETA " + short_duration(static_cast<double>(eta->count())) : std::string();
    const std::string frames = frames_of(job);
    bar.update(job.tiles_done(), std::max<std::size_t>(1, job.tiles_total()),
               frames.empty() ? eta_text : eta_text.empty() ? frames : frames + ", " + eta_text);
    if (!terminal && job.state() != shown) {
      fmt::print("job {}: {} ({}{})\n", job_id, to_string(job.state()), progress_of(job),
                 eta_text.empty() ? "" : ", " + eta_text);
      std::fflush(stdout);
      shown = job.state();
    }
    if (event.has_tile_failed()) {
      const v1::TileFailed& f = event.tile_failed();
      fmt::print(stderr, "job {}: {} failed on {}: {}{}\n", job_id, describe_units(f.tile_index(), f.tile_count()),
                 f.worker(), f.reason(), f.will_retry() ? " (will retry)" : "");
    }
    if (also) also(event);
  });
  return last;
}

int exit_code_of(const v1::Job& job) {
  if (job.state() == v1::JOB_STATE_SUCCEEDED) return 0;
  fmt::print(stderr, "job {} {}{}\n", job.job_id(), to_string(job.state()),
             job.failure_reason().empty() ? "" : ": " + job.failure_reason());
  return 1;
}

}  // namespace farm
