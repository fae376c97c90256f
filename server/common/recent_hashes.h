#pragma once
// A bounded set of hashes, safe to share between threads: the most recent `capacity` inserted
// are kept, the oldest forgotten first. For what a scheduler remembers about scenes (which
// passed their check, which a worker has been sent), where forgetting costs only a repetition.
#include <cstddef>
#include <deque>
#include <mutex>
#include <string>
#include <unordered_set>

namespace farm {

class RecentHashes {
 public:
  explicit RecentHashes(std::size_t capacity) : capacity_(capacity) {}

  bool contains(const std::string& hash) const {
    std::lock_guard lock(mutex_);
    return set_.count(hash) > 0;
  }

  void insert(const std::string& hash) {
    std::lock_guard lock(mutex_);
    if (!set_.insert(hash).second) return;
    order_.push_back(hash);
    if (order_.size() > capacity_) {
      set_.erase(order_.front());
      order_.pop_front();
    }
  }

 private:
  const std::size_t capacity_;
  mutable std::mutex mutex_;  // guards the two below
  std::unordered_set<std::string> set_;
  std::deque<std::string> order_;  // oldest first
};

}  // namespace farm
