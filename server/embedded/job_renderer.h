#pragma once
// One job rendered to an EXR and its preview, on the embedded farm or on a scheduler's farm:
// what regression suites and grading rubrics both need. Safe to call from several threads.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "server/client/job_submission.h"
#include "server/client/scheduler_connection.h"

namespace farm {

class EmbeddedFarm;

class JobRenderer {
 public:
  // `scheduler` empty: an embedded farm with `threads` render threads (0: all cores).
  JobRenderer(std::optional<SchedulerConnection> scheduler, int threads);
  ~JobRenderer();
  JobRenderer(const JobRenderer&) = delete;
  JobRenderer& operator=(const JobRenderer&) = delete;

  // Renders `submission` and leaves its EXR at `exr` and its sRGB preview at `preview`. Throws
  // std::runtime_error saying why when the job does not succeed (ServiceError when the scheduler
  // cannot be reached).
  void render(JobSubmission submission, const std::filesystem::path& exr, const std::filesystem::path& preview);

 private:
  std::optional<SchedulerConnection> scheduler_;
  std::unique_ptr<EmbeddedFarm> farm_;
};

}  // namespace farm
