#include "server/cli/watch_command.h"

#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "renderer/util/file_extension.h"
#include "server/cli/job_display.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"

namespace farm {

namespace {

struct WatchOptions {
  JobOnScheduler target;
  std::filesystem::path preview;  // empty: none
};

// The preview to show after `event`: a frame of sample passes refines after each pass (its
// progressive preview); a frame without passes is shown once merged.
std::optional<std::pair<v1::ResultKind, int>> preview_after(const v1::JobEvent& event) {
  if (event.has_pass_finished()) return std::pair{v1::RESULT_KIND_PROGRESSIVE, event.pass_finished().frame()};
  if (event.has_frame_finished() && event.job().passes() <= 1) {
    return std::pair{v1::RESULT_KIND_PREVIEW, event.frame_finished().frame()};
  }
  return std::nullopt;
}

}  // namespace

void add_watch_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<WatchOptions>();
  CLI::App* watch = app.add_subcommand(
      "watch", "Follow a job with a progress bar until it ends; a job that has ended has its event log replayed");
  add_job_on_scheduler_options(*watch, o->target);
  watch->add_option("--preview", o->preview,
                    "Keep this PNG up to date with the newest preview while the job renders: after each "
                    "sample pass of a frame (render.pass_spp), and after each merged frame")
      ->check([](const std::string& s) {
        return lowercase_extension(s) == ".png" ? std::string() : fmt::format("expected a .png file, got '{}'", s);
      });
  watch->footer("Exit codes: 0 the job succeeded, 1 it failed or was cancelled.");
  commands.add(watch, [o] {
    SchedulerClient client(resolve_scheduler_connection(o->target.scheduler));
    o->target.job_id = client.resolve_job_id(o->target.job_id);
    if (const v1::Job now = client.get(o->target.job_id); is_final(now.state())) {
      // Nothing more will happen: what did happen is replayed from its log.
      for (const v1::JobLogEntry& e : client.log(o->target.job_id)) print_log_entry(e);
      print_job(now);
      return exit_code_of(now);
    }
    const auto refresh = [&](const v1::JobEvent& event) {
      if (o->preview.empty()) return;
      const auto wanted = preview_after(event);
      if (!wanted) return;
      try {
        // Through a temporary file: a viewer never sees half a PNG.
        client.fetch(o->target.job_id, wanted->first, [&](const std::string&) { return o->preview; },
                     wanted->second);
      } catch (const std::exception& e) {
        // The job goes on; the next pass or frame tries again.
        fmt::print(stderr, "farm watch: preview of frame {}: {}\n", wanted->second, e.what());
      }
    };
    const v1::Job last = follow(client, o->target.job_id, refresh);
    print_job(last);
    return exit_code_of(last);
  });
}

}  // namespace farm
