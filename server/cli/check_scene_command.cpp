#include "server/cli/check_scene_command.h"

#include <cstdint>
#include <filesystem>
#include <memory>

#include "server/scheduler/jobs/scene_check.h"

namespace farm {

namespace {

struct CheckSceneOptions {
  std::filesystem::path job;
  std::filesystem::path asset_root;
  std::uint64_t memory_limit = 0;
};

}  // namespace

void add_check_scene_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<CheckSceneOptions>();
  CLI::App* check = app.add_subcommand("check-scene", "Load a job's scene under a memory limit (run by farm scheduler)");
  check->group("");  // internal: not listed by --help
  check->add_option("job", o->job, "The job file")->required();
  check->add_option("--asset-root", o->asset_root, "Folder the job's models must lie in")->required();
  check->add_option("--memory-limit", o->memory_limit, "Address space limit in bytes")
      ->required()
      ->check(CLI::Range(std::uint64_t{64} << 20, std::uint64_t{1} << 50));
  commands.add(check, [o] { return check_scene_in_this_process(o->job, o->asset_root, o->memory_limit); });
}

}  // namespace farm
