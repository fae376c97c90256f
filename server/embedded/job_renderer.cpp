#include "server/embedded/job_renderer.h"

#include <fmt/format.h>

#include <stdexcept>

#include "server/client/scheduler_client.h"
#include "server/embedded/embedded_farm.h"

namespace farm {

JobRenderer::JobRenderer(std::optional<SchedulerConnection> scheduler, int threads) : scheduler_(std::move(scheduler)) {
  if (scheduler_) return;
  EmbeddedFarmOptions options;
  options.threads = threads;
  farm_ = std::make_unique<EmbeddedFarm>(options);
}

JobRenderer::~JobRenderer() = default;

void JobRenderer::render(JobSubmission submission, const std::filesystem::path& exr, const std::filesystem::path& preview) {
  if (farm_) {
    submission.job.output.image = exr;
    submission.job.output.preview = preview;
    const EmbeddedResult result = farm_->run_local(submission);
    if (result.job.state() != v1::JOB_STATE_SUCCEEDED) {
      throw std::runtime_error(fmt::format("the render {}: {}", to_string(result.job.state()), result.job.failure_reason()));
    }
    return;
  }
  // One client per call: a stub is cheap, and calls from several threads stay independent.
  SchedulerClient client(*scheduler_);
  client.upload_missing(submission);
  const v1::Job job = client.submit(submission, 0);
  const v1::Job last = client.watch(job.job_id(), {});
  if (last.state() != v1::JOB_STATE_SUCCEEDED) {
    throw std::runtime_error(fmt::format("the render {}: {}", to_string(last.state()), last.failure_reason()));
  }
  client.fetch(job.job_id(), v1::RESULT_KIND_EXR, [&](const std::string&) { return exr; });
  client.fetch(job.job_id(), v1::RESULT_KIND_PREVIEW, [&](const std::string&) { return preview; });
}

}  // namespace farm
