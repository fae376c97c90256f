#pragma once
// What the scheduler tests that render for real set up alike: a scheduler core whose asset store
// holds the Cornell box jobs' files, and the options of an in-process worker reading them there.
#include <filesystem>

#include "server/common/log.h"
#include "server/scheduler/scheduler_core.h"
#include "server/worker/tile_renderer.h"

namespace farm::test {

void add_cornell_assets(SchedulerCore& core);

// An in-process worker of a scheduler whose data folder is `data_dir` (its assets/ the worker's
// store), laying its scenes out in `cache_dir`.
TileRendererOptions in_process_worker_options(const std::filesystem::path& data_dir,
                                              const std::filesystem::path& cache_dir, int threads,
                                              LogLevel log_level = LogLevel::info);

}  // namespace farm::test
