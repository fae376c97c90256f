#pragma once
// Memory for large arrays read at random: a frame's buffers (uninitialized_array.h) and a BVH's
// nodes and leaf blocks (bvh.h, mesh_accel.cpp). From 4 MiB up, such an array is placed on 2 MiB
// boundaries and offered to the kernel for transparent huge pages (madvise: a hint, plain pages
// where the kernel has none), so that a walk over a large tree misses in the TLB far less: a
// 2M-triangle model's incoherent closest hits ran 12% faster with them (docs/architecture.md
// 8.6). Below 4 MiB the rounding to 2 MiB would waste too much for the few pages saved.
#include <cstddef>
#include <limits>
#include <new>

namespace farm {

// The size allocate_large_array gives for `bytes`: a multiple of 4 KiB, or of 2 MiB from 4 MiB up.
std::size_t large_array_size(std::size_t bytes);
// large_array_size(bytes) bytes, page-aligned, 2 MiB-aligned (and huge pages asked for) from 4 MiB
// up. Throws std::bad_alloc.
void* allocate_large_array(std::size_t bytes);
void free_large_array(void* p) noexcept;

// Below this an array comes from the ordinary heap, not allocate_large_array (both
// LargeArrayAllocator and UninitializedArray's frame memory draw the line here).
inline constexpr std::size_t kLargeArrayMinBytes = std::size_t{64} << 10;

// For std::vector: arrays of kLargeArrayMinBytes or more come from allocate_large_array.
template <typename T>
struct LargeArrayAllocator {
  using value_type = T;

  LargeArrayAllocator() = default;
  template <typename U>
  LargeArrayAllocator(const LargeArrayAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    if (n > std::numeric_limits<std::size_t>::max() / sizeof(T)) throw std::bad_alloc();
    if (n * sizeof(T) < kLargeArrayMinBytes) {
      return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t{alignof(T)}));
    }
    return static_cast<T*>(allocate_large_array(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) < kLargeArrayMinBytes) {
      ::operator delete(p, std::align_val_t{alignof(T)});
    } else {
      free_large_array(p);
    }
  }
  template <typename U>
  bool operator==(const LargeArrayAllocator<U>&) const noexcept {
    return true;
  }
};

}  // namespace farm
