#include "renderer/util/uninitialized_array.h"

#include <mutex>
#include <vector>

#include "renderer/util/huge_pages.h"

namespace farm::detail {
namespace {

constexpr std::size_t kRecycledBytesLimit = std::size_t{1} << 30;

// Blocks freed by one frame, kept for the next: a fresh block costs a page fault and a
// kernel-zeroed page for every 4 KiB (or 2 MiB) on first touch, which for a big scene is a
// sizeable part of the frame set-up, and faults from several threads contend in the kernel.
class BlockRecycler {
 public:
  void* take(std::size_t bytes) {
    std::lock_guard lock(mutex_);
    // The smallest kept block that fits and is not more than twice too big.
    std::size_t best = blocks_.size();
    for (std::size_t i = 0; i < blocks_.size(); ++i) {
      const std::size_t size = blocks_[i].size;
      if (size >= bytes && size <= 2 * bytes && (best == blocks_.size() || size < blocks_[best].size))
        best = i;
    }
    if (best == blocks_.size()) return nullptr;
    void* p = blocks_[best].memory;
    kept_bytes_ -= blocks_[best].size;
    blocks_.erase(blocks_.begin() + static_cast<std::ptrdiff_t>(best));
    return p;
  }

  bool keep(void* p, std::size_t size) {
    std::lock_guard lock(mutex_);
    if (kept_bytes_ + size > kRecycledBytesLimit) return false;
    blocks_.push_back({p, size});
    kept_bytes_ += size;
    return true;
  }

 private:
  struct Block {
    void* memory;
    std::size_t size;
  };
  std::mutex mutex_;
  std::vector<Block> blocks_;
  std::size_t kept_bytes_ = 0;
};

// Never destroyed: threads that outlive main's static destructors (a pool's, joined by its own
// static destructor) free their thread_local arrays here as they end, and a recycler destroyed
// before them was written after its end (valgrind: farm regress aborting with "double free" as
// the pool's threads ended, once igzip's per-thread buffers were the recycler's first blocks).
BlockRecycler& recycler() {
  static BlockRecycler* const instance = new BlockRecycler;
  return *instance;
}

}  // namespace

void* allocate_frame_memory(std::size_t bytes) {
  if (bytes == 0) bytes = 1;
  if (bytes < kLargeArrayMinBytes) {
    void* p = std::malloc(bytes);
    if (!p) throw std::bad_alloc();
    return p;
  }
  if (void* p = recycler().take(large_array_size(bytes))) return p;
  return allocate_large_array(bytes);
}

void free_frame_memory(void* p, std::size_t bytes) {
  if (!p) return;
  if (bytes < kLargeArrayMinBytes) {
    std::free(p);
  } else if (!recycler().keep(p, large_array_size(bytes))) {
    free_large_array(p);
  }
}

}  // namespace farm::detail
