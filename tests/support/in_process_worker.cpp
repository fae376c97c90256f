#include "tests/support/in_process_worker.h"

#include "server/common/read_whole_file.h"
#include "tests/support/job_specs.h"

namespace farm::test {

void add_cornell_assets(SchedulerCore& core) {
  for (const auto& [path, file] : cornell_assets()) core.assets().add(read_whole_file(file, "asset"));
}

TileRendererOptions in_process_worker_options(const std::filesystem::path& data_dir,
                                              const std::filesystem::path& cache_dir, int threads,
                                              LogLevel log_level) {
  TileRendererOptions r;
  r.blobs_dir = data_dir / "assets";
  r.cache_dir = cache_dir;
  r.threads = threads;
  r.log_level = log_level;
  return r;
}

}  // namespace farm::test
