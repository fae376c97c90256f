#include "server/cli/client_commands.h"

#include <fmt/format.h>

#include <chrono>
#include <ctime>

#include "renderer/scene/input_error.h"
#include "server/cli/progress_bar.h"
#include "server/client/job_submission.h"
#include "server/client/scheduler_client.h"
#include "server/common/job_state.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

void add_scheduler_option(CLI::App* command, ClientOptions& o) {
  command->add_option("--scheduler", o.scheduler,
                      "Scheduler HOST:PORT (default: $FARM_SCHEDULER, else localhost:50051)");
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

std::string progress_of(const v1::Job& job) {
  return fmt::format("{}/{} tiles", job.tiles_done(), job.tiles_total());
}

void print_job(const v1::Job& job) {
  fmt::print("job {} '{}': {}, {}\n", job.job_id(), job.name(), to_string(job.state()), progress_of(job));
  fmt::print("  {} engine, {}x{}, scene {}\n", job.engine(), job.width(), job.height(),
             job.scene_hash().substr(0, 16));
  fmt::print("  submitted {}, started {}, finished {}\n", local_time(job.submitted_at()),
             local_time(job.started_at()), local_time(job.finished_at()));
  if (job.tile_failures() > 0) fmt::print("  tile retries: {}\n", job.tile_failures());
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

// Follows a job to its end with a progress bar (on a terminal) or a line per state change.
v1::Job follow(SchedulerClient& client, const std::string& job_id) {
  const bool terminal = ProgressBar::stderr_is_terminal();
  ProgressBar bar(fmt::format("job {}", job_id), terminal);
  v1::JobState shown = v1::JOB_STATE_UNSPECIFIED;
  const v1::Job last = client.watch(job_id, [&](const v1::JobEvent& event) {
    const v1::Job& job = event.job();
    bar.update(job.tiles_done(), std::max<std::size_t>(1, job.tiles_total()));
    if (!terminal && job.state() != shown) {
      fmt::print("job {}: {} ({})\n", job_id, to_string(job.state()), progress_of(job));
      std::fflush(stdout);
      shown = job.state();
    }
    if (event.has_tile_failed()) {
      const v1::TileFailed& f = event.tile_failed();
      fmt::print(stderr, "job {}: {} failed on {}: {}{}\n", job_id, describe_tiles(f.tile_index(), f.tile_count()),
                 f.worker(), f.reason(), f.will_retry() ? " (will retry)" : "");
    }
  });
  return last;
}

int exit_code_of(const v1::Job& job) {
  if (job.state() == v1::JOB_STATE_SUCCEEDED) return 0;
  fmt::print(stderr, "job {} {}{}\n", job.job_id(), to_string(job.state()),
             job.failure_reason().empty() ? "" : ": " + job.failure_reason());
  return 1;
}

// Fetches the EXR and, if the job has one, the preview; `where` picks the file for each.
void fetch_results(SchedulerClient& client, const std::string& job_id,
                   const std::function<fs::path(v1::ResultKind, const std::string&)>& where,
                   bool want_preview) {
  const fs::path exr = client.fetch(job_id, v1::RESULT_KIND_EXR,
                                    [&](const std::string& name) { return where(v1::RESULT_KIND_EXR, name); });
  fmt::print("wrote {}\n", exr.string());
  if (!want_preview) return;
  try {
    const fs::path png = client.fetch(
        job_id, v1::RESULT_KIND_PREVIEW, [&](const std::string& name) { return where(v1::RESULT_KIND_PREVIEW, name); });
    fmt::print("wrote {}\n", png.string());
  } catch (const InputError&) {
    // The job asked for no preview.
  }
}

int run_submit(const ClientOptions& o) {
  const JobSubmission submission = make_job_submission(o.job_file, o.load, o.overrides);
  SchedulerClient client(resolve_scheduler_address(o.scheduler));
  const std::size_t uploaded = client.upload_missing(submission);
  const v1::Job job = client.submit(submission, o.priority);
  fmt::print("{}\n", job.job_id());
  fmt::print(stderr, "submitted '{}' to {}: {} tiles, {} of {} assets uploaded\n", job.name(), client.address(),
             job.tiles_total(), uploaded, submission.spec.assets_size());
  if (!o.wait) return 0;
  const v1::Job last = follow(client, job.job_id());
  if (last.state() != v1::JOB_STATE_SUCCEEDED) return exit_code_of(last);
  // Like `farm render`: the results land where the job's output section says.
  fetch_results(client, job.job_id(),
                [&](v1::ResultKind kind, const std::string&) {
                  return kind == v1::RESULT_KIND_EXR ? submission.job.output.image : submission.job.output.preview;
                },
                !submission.job.output.preview.empty());
  return 0;
}

int run_status(const ClientOptions& o) {
  SchedulerClient client(resolve_scheduler_address(o.scheduler));
  if (!o.job_id.empty()) {
    print_job(client.get(o.job_id));
    return 0;
  }
  const std::vector<v1::Job> jobs = client.list();
  if (jobs.empty()) {
    fmt::print("no jobs on {}\n", client.address());
    return 0;
  }
  fmt::print("{:<36} {:<20} {:<10} {:>13} {:<8} {:>11} {}\n", "ID", "NAME", "STATE", "PROGRESS", "ENGINE", "SIZE",
             "SUBMITTED");
  for (const v1::Job& job : jobs) {
    fmt::print("{:<36} {:<20} {:<10} {:>13} {:<8} {:>11} {}\n", job.job_id(), job.name().substr(0, 20),
               to_string(job.state()), progress_of(job), job.engine(), fmt::format("{}x{}", job.width(), job.height()),
               local_time(job.submitted_at()));
  }
  return 0;
}

int run_watch(const ClientOptions& o) {
  SchedulerClient client(resolve_scheduler_address(o.scheduler));
  const v1::Job last = follow(client, o.job_id);
  print_job(last);
  return exit_code_of(last);
}

int run_cancel(const ClientOptions& o) {
  SchedulerClient client(resolve_scheduler_address(o.scheduler));
  const v1::Job job = client.cancel(o.job_id);
  fmt::print("job {}: {} ({})\n", job.job_id(), to_string(job.state()), progress_of(job));
  return 0;
}

int run_fetch(const ClientOptions& o) {
  SchedulerClient client(resolve_scheduler_address(o.scheduler));
  const v1::Job job = client.get(o.job_id);
  if (job.state() != v1::JOB_STATE_SUCCEEDED) {
    throw InputError(fmt::format("job {} is {}: nothing to fetch yet{}", o.job_id, to_string(job.state()),
                                 job.failure_reason().empty() ? "" : " (" + job.failure_reason() + ")"));
  }
  fetch_results(client, o.job_id,
                [&](v1::ResultKind kind, const std::string& name) {
                  const std::string fallback = job.name() + (kind == v1::RESULT_KIND_EXR ? ".exr" : ".png");
                  return o.output_dir / (name.empty() ? fallback : name);
                },
                true);
  return 0;
}

}  // namespace

void add_client_commands(CLI::App& app, ClientCommands& c) {
  ClientOptions& o = c.options;
  c.submit = app.add_subcommand("submit", "Send a job and its assets to a scheduler; prints the job id");
  c.submit->add_option("job", o.job_file, "Job file (JSON)")->required()->check(CLI::ExistingFile);
  add_scheduler_option(c.submit, o);
  c.submit->add_flag("--wait", o.wait,
                     "Follow the job to its end, then download the EXR and preview to the job's "
                     "output paths (exit 1 if the job fails or is cancelled)");
  c.submit->add_option("--priority", o.priority, "Higher runs first; equal priorities in submission order")
      ->capture_default_str();
  c.submit->add_option("--asset-root", o.load.asset_root,
                       "Folder that model files must lie in (default: the job file's folder)")
      ->check(CLI::ExistingDirectory);
  c.submit->add_option("--engine", o.overrides.engine, "Replace render.engine")
      ->check(CLI::IsMember({"raster", "whitted", "path"}));
  c.submit->add_option("--width", o.overrides.width, "Replace render.width")->check(CLI::Range(1, 16384));
  c.submit->add_option("--height", o.overrides.height, "Replace render.height")->check(CLI::Range(1, 16384));
  c.submit->add_option("--spp", o.overrides.spp, "Replace render.spp")->check(CLI::Range(1, 1 << 20));
  c.submit->add_option("--tile-size", o.overrides.tile_size, "Replace render.tile_size")
      ->check(CLI::Range(1, 16384));
  c.submit->footer("Assets are content-addressed (SHA-256): only those the scheduler lacks are uploaded.");

  c.status = app.add_subcommand("status", "List the scheduler's jobs, or show one");
  c.status->add_option("id", o.job_id, "Job id (default: list all jobs)");
  add_scheduler_option(c.status, o);

  c.watch = app.add_subcommand("watch", "Follow a job with a progress bar until it ends");
  c.watch->add_option("id", o.job_id, "Job id")->required();
  add_scheduler_option(c.watch, o);
  c.watch->footer("Exit codes: 0 the job succeeded, 1 it failed or was cancelled.");

  c.cancel = app.add_subcommand("cancel", "Cancel a job: its queued tiles are dropped, running ones stopped");
  c.cancel->add_option("id", o.job_id, "Job id")->required();
  add_scheduler_option(c.cancel, o);

  c.fetch = app.add_subcommand("fetch", "Download a finished job's EXR and preview");
  c.fetch->add_option("id", o.job_id, "Job id")->required();
  c.fetch->add_option("-o,--output", o.output_dir, "Folder to write into")->capture_default_str();
  add_scheduler_option(c.fetch, o);
}

int run_client_command(const ClientCommands& c) {
  if (c.submit->parsed()) return run_submit(c.options);
  if (c.status->parsed()) return run_status(c.options);
  if (c.watch->parsed()) return run_watch(c.options);
  if (c.cancel->parsed()) return run_cancel(c.options);
  if (c.fetch->parsed()) return run_fetch(c.options);
  return -1;
}

}  // namespace farm
