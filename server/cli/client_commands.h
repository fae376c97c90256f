#pragma once
// The farm's client commands: `farm submit`, `status`, `watch`, `cancel` and `fetch`, talking to
// a scheduler (--scheduler ADDR, else $FARM_SCHEDULER, else localhost:50051).
#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>

#include "renderer/scene/job.h"
#include "server/cli/render_command.h"

namespace farm {

struct ClientOptions {
  std::string scheduler;  // empty: $FARM_SCHEDULER or the default
  // submit
  std::filesystem::path job_file;
  JobLoadOptions load;
  RenderOverrides overrides;
  bool wait = false;
  int priority = 0;
  // status, watch, cancel, fetch
  std::string job_id;
  std::filesystem::path output_dir = ".";
};

struct ClientCommands {
  ClientOptions options;
  CLI::App* submit = nullptr;
  CLI::App* status = nullptr;
  CLI::App* watch = nullptr;
  CLI::App* cancel = nullptr;
  CLI::App* fetch = nullptr;
};

// Adds the five subcommands to `app`; `commands` must outlive the parse.
void add_client_commands(CLI::App& app, ClientCommands& commands);

// Runs whichever of them was given; returns its exit code, or -1 when none was. Throws InputError
// for bad input (exit code 2) and runtime_error when the scheduler cannot be reached (1).
int run_client_command(const ClientCommands& commands);

}  // namespace farm
