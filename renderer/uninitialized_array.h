#pragma once
// A fixed-size array whose elements start uninitialized, for large per-frame buffers that are
// then filled in parallel: no thread first zeroes memory that others overwrite, and each page is
// first touched by the thread that fills it. Large arrays ask the kernel for transparent huge
// pages, which cuts the page faults of a fresh frame's buffers by up to 512x.
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>

namespace farm {

namespace detail {
void* allocate_frame_memory(std::size_t bytes);  // huge-page friendly for large sizes
struct FreeFrameMemory {
  void operator()(void* p) const { std::free(p); }
};
}  // namespace detail

template <typename T>
class UninitializedArray {
  static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>,
                "elements must need no construction or destruction");

 public:
  // Makes room for n elements, whose values are then unspecified. Memory is reused when it is
  // large enough already.
  void allocate(std::size_t n) {
    if (n > capacity_) {
      data_.reset(static_cast<T*>(detail::allocate_frame_memory(n * sizeof(T))));
      capacity_ = n;
    }
    size_ = n;
  }
  std::size_t size() const { return size_; }
  T& operator[](std::size_t i) { return data_.get()[i]; }
  const T& operator[](std::size_t i) const { return data_.get()[i]; }
  T* begin() { return data_.get(); }
  T* end() { return data_.get() + size_; }
  const T* begin() const { return data_.get(); }
  const T* end() const { return data_.get() + size_; }

 private:
  std::unique_ptr<T, detail::FreeFrameMemory> data_;
  std::size_t size_ = 0, capacity_ = 0;
};

}  // namespace farm
