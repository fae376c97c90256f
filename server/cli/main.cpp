// `farm`: the render farm's command line. Each command lives in its own file under server/cli/
// and registers itself in a CommandTable; this file parses, runs the one given and maps failures
// to exit codes: 0 ok, 2 bad input, 1 internal error.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cstdio>
#include <exception>
#include <string>

#include "renderer/util/input_error.h"
#include "server/cli/bench_command.h"
#include "server/cli/check_scene_command.h"
#include "server/cli/command_table.h"
#include "server/cli/compare_command.h"
#include "server/cli/fetch_command.h"
#include "server/cli/grade_command.h"
#include "server/cli/health_command.h"
#include "server/cli/info_command.h"
#include "server/cli/job_action_commands.h"
#include "server/cli/log_command.h"
#include "server/cli/regress_command.h"
#include "server/cli/render_command.h"
#include "server/cli/scheduler_command.h"
#include "server/cli/status_command.h"
#include "server/cli/submit_command.h"
#include "server/cli/token_command.h"
#include "server/cli/validate_command.h"
#include "server/cli/watch_command.h"
#include "server/cli/worker_command.h"
#include "server/cli/workers_command.h"
#include "server/common/service_error.h"
#include "server/common/version.h"

namespace {

constexpr int kExitBadInput = 2;
constexpr int kExitInternal = 1;

constexpr const char* kOverview =
    "farm: render farm batch service.\n"
    "  farm render JOB   render a job locally to EXR + PNG preview\n"
    "  farm info FILE    show what a model or job file contains\n"
    "  farm validate JOB compare our BVH's ray hits with Embree's on a job's scene\n"
    "  farm compare REF NEW  compare an image with its reference (exact, idiff threshold, PSNR, SSIM,\n"
    "                    FLIP, z-test): PASS / WARN / FAIL\n"
    "  farm regress SUITE render a regression suite, compare with references; JUnit, HTML report\n"
    "  farm grade RUBRIC SUBMISSIONS  score a class's submissions against farm-rendered references\n"
    "  farm bench raster measure rasterizer speed and thread scaling\n"
    "  farm bench rt     compare our BVHs with Embree\n"
    "  farm bench path   path tracer throughput (and Mitsuba's, side by side)\n"
    "  farm bench farm   the farm's overhead over loopback, jobs per second\n"
    "  farm bench render the whole farm render command against the bare engine frame\n"
    "  farm scheduler    serve jobs over gRPC: units to workers, merged EXR out\n"
    "  farm worker       render units for a scheduler over gRPC\n"
    "  farm submit JOB   send a job to a scheduler (status, watch, cancel, fetch follow it)";

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{kOverview};
  app.require_subcommand(1);
  app.set_version_flag("--version", "farm " + std::string(farm::kFarmVersion));

  farm::CommandTable commands;
  farm::add_render_command(app, commands);
  farm::add_info_command(app, commands);
  farm::add_validate_command(app, commands);
  farm::add_compare_command(app, commands);
  farm::add_regress_command(app, commands);
  farm::add_grade_command(app, commands);
  farm::add_bench_command(app, commands);
  farm::add_worker_command(app, commands);
  farm::add_scheduler_command(app, commands);
  farm::add_submit_command(app, commands);
  farm::add_status_command(app, commands);
  farm::add_watch_command(app, commands);
  farm::add_job_action_commands(app, commands);
  farm::add_log_command(app, commands);
  farm::add_workers_command(app, commands);
  farm::add_health_command(app, commands);
  farm::add_fetch_command(app, commands);
  farm::add_token_command(app, commands);
  farm::add_check_scene_command(app, commands);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with exit code 0; the rest are bad input.
    const int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }

  try {
    return commands.run_parsed();
  } catch (const farm::InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kExitBadInput;
  } catch (const farm::ServiceError& e) {
    fmt::print(stderr, "error: {}\n", e.what());  // e.g. the scheduler is not reachable
    return kExitInternal;
  } catch (const std::exception& e) {
    fmt::print(stderr, "internal error: {}\n", e.what());
    return kExitInternal;
  }
}
