#include "server/cli/job_file_options.h"

namespace farm {

void add_asset_root_option(CLI::App& command, JobLoadOptions& load) {
  // A model outside the job's folder is the first thing a new user meets (jobs/cow.json names
  // ../shared/assets): the refusal says how to allow it.
  load.asset_root_hint = "give --asset-root DIR (a folder that holds both the job's models and their files) to let "
                         "the job reach it";
  command.add_option("--asset-root", load.asset_root,
                     "Folder that a job's model files must lie in (default: the job file's folder)")
      ->check(CLI::ExistingDirectory);
}

void add_job_file_options(CLI::App& command, std::filesystem::path& job_file, JobLoadOptions& load) {
  command.add_option("job", job_file, "Job file (JSON, see jobs/README.md)")
      ->required()
      ->check(CLI::ExistingFile);
  add_asset_root_option(command, load);
}

}  // namespace farm
