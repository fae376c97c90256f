#include "server/scheduler/jobs/progressive_previews.h"

#include <vector>

#include "renderer/image/preview.h"
#include "server/common/disk_full.h"

namespace farm {

void ProgressivePreviews::update(const std::string& job_id, const JobInfo& info, int frame,
                                 const std::filesystem::path& file) {
  const int passes = info.passes();
  if (passes <= 1 || !assembly_.reads_parts_back()) return;
  const int complete = store_.frames().complete_passes(job_id, frame);
  if (complete <= 0 || complete >= passes) return;  // nothing to show yet, or the merge's turn
  const Key key{job_id, frame};
  {
    std::lock_guard lock(mutex_);
    const auto it = announced_.find(key);
    if (it != announced_.end() && it->second >= complete - 1) return;
  }
  std::unique_ptr<Fold> fold = take(key);
  const FrameLayout layout = info.frame(frame);
  if (fold->pixels.rect().empty() || fold->passes > complete) {
    fold->pixels.reset(layout.image, layout.aovs);
    fold->passes = 0;
  }
  std::vector<FramePart> parts;
  for (const FramePart& p : store_.frames().frame_parts(job_id, frame, complete)) {
    if (p.pass >= fold->passes) parts.push_back(p);
  }
  // A fold that throws half way is dropped (not put back): the next update starts afresh.
  assembly_.fold(job_id, layout, parts, fold->pixels);
  fold->passes = complete;
  try {
    write_preview(fold->pixels.resolve(), file);
  } catch (const std::exception&) {
    rethrow_as_disk_full(file.parent_path());
  }
  put_back(key, std::move(fold));
  publish(job_id, frame, complete - 1, passes);
}

void ProgressivePreviews::frame_merged(const std::string& job_id, const JobInfo& info, int frame) {
  const int passes = info.passes();
  if (passes <= 1) return;
  {
    std::lock_guard lock(mutex_);
    std::erase_if(folds_, [&](const auto& entry) { return entry.first == Key{job_id, frame}; });
  }
  publish(job_id, frame, passes - 1, passes);  // unless announced already
}

void ProgressivePreviews::parts_taken_back(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  std::erase_if(folds_, [&](const auto& entry) { return entry.first.first == job_id; });
  ++taken_back_[job_id];
}

void ProgressivePreviews::forget_job(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  std::erase_if(folds_, [&](const auto& entry) { return entry.first.first == job_id; });
  std::erase_if(announced_, [&](const auto& entry) { return entry.first.first == job_id; });
  taken_back_.erase(job_id);
}

std::unique_ptr<ProgressivePreviews::Fold> ProgressivePreviews::take(const Key& key) {
  std::lock_guard lock(mutex_);
  for (auto it = folds_.begin(); it != folds_.end(); ++it) {
    if (it->first != key) continue;
    std::unique_ptr<Fold> fold = std::move(it->second);
    folds_.erase(it);
    return fold;
  }
  auto fold = std::make_unique<Fold>();
  fold->taken_back = taken_back_[key.first];
  return fold;
}

void ProgressivePreviews::put_back(const Key& key, std::unique_ptr<Fold> fold) {
  std::lock_guard lock(mutex_);
  if (fold->taken_back != taken_back_[key.first]) return;  // it may hold parts taken back since
  folds_.emplace_front(key, std::move(fold));
  while (folds_.size() > kKeptFrames) folds_.pop_back();
}

void ProgressivePreviews::publish(const std::string& job_id, int frame, int pass, int passes) {
  {
    std::lock_guard lock(mutex_);
    int& newest = announced_.try_emplace({job_id, frame}, -1).first->second;
    if (pass <= newest) return;
    newest = pass;
  }
  events_.publish(job_id, [&](v1::JobEvent& event) {
    v1::PassFinished& p = *event.mutable_pass_finished();
    p.set_frame(frame);
    p.set_pass(pass);
    p.set_passes(passes);
  });
}

}  // namespace farm
