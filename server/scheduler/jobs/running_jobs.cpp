#include "server/scheduler/jobs/running_jobs.h"

#include <algorithm>
#include <stdexcept>

#include "server/common/job_state.h"
#include "server/common/scene_materializer.h"

namespace farm {

FrameLayout JobInfo::frame(int f) const {
  FrameLayout layout{Rect{0, 0, job->render.width, job->render.height}, job->render.aovs, f, {}};
  const int passes = pass_count(job->render);
  for (int p = 0; p < passes; ++p) layout.passes.push_back(pass_samples(job->render, p));
  return layout;
}

std::shared_ptr<const JobInfo> RunningJobs::get(const std::string& job_id) {
  {
    std::lock_guard lock(mutex_);
    if (auto it = jobs_.find(job_id); it != jobs_.end()) return it->second;
  }
  // A job an earlier process queued: its spec from the store, laid out and parsed once.
  std::optional<v1::Job> job = store_.jobs().get_job(job_id);
  std::optional<v1::JobSpec> spec = store_.jobs().get_spec(job_id);
  if (!job || !spec) throw std::runtime_error("no spec for job " + job_id);
  auto info = std::make_shared<JobInfo>();
  info->spec = std::make_shared<const v1::JobSpec>(std::move(*spec));
  info->scene_hash = job->scene_hash();
  info->job = std::make_shared<const Job>(
      materialize_scene(*info->spec, info->scene_hash, assets_, data_dir_).job);
  if (is_final(job->state())) return info;  // nobody forgets a final job again
  return add(job_id, std::move(info));
}

std::shared_ptr<const JobInfo> RunningJobs::add(const std::string& job_id,
                                                std::shared_ptr<const JobInfo> info) {
  std::lock_guard lock(mutex_);
  // Two slots may parse a resumed job at once: the first kept wins, so all share one.
  return jobs_.emplace(job_id, std::move(info)).first->second;
}

void RunningJobs::add_unit_cost(const std::string& job_id, double ms) {
  std::lock_guard lock(mutex_);
  auto [it, added] = ms_per_tile_.emplace(job_id, ms);
  if (!added) it->second = 0.5 * (it->second + ms);  // tiles differ: follow the recent ones
}

std::optional<double> RunningJobs::unit_cost(const std::string& job_id) const {
  std::lock_guard lock(mutex_);
  const auto it = ms_per_tile_.find(job_id);
  if (it == ms_per_tile_.end()) return std::nullopt;
  return it->second;
}

std::size_t RunningJobs::forget(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  jobs_.erase(job_id);
  ms_per_tile_.erase(job_id);
  return std::max(jobs_.size(), ms_per_tile_.size());
}

std::size_t RunningJobs::count() const {
  std::lock_guard lock(mutex_);
  return std::max(jobs_.size(), ms_per_tile_.size());
}

}  // namespace farm
