#pragma once
// A fixed-size array whose elements start uninitialized, for large per-frame buffers that are
// then filled in parallel: no thread first zeroes memory that others overwrite. Large arrays ask
// the kernel for transparent huge pages, and their memory is recycled for the next frame rather
// than returned to the kernel, so a new frame does not fault in and zero its buffers afresh.
#include <cstddef>
#include <cstdlib>
#include <utility>
#include <type_traits>

namespace farm {

namespace detail {
void* allocate_frame_memory(std::size_t bytes);
void free_frame_memory(void* p, std::size_t bytes);
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
      release();
      data_ = static_cast<T*>(detail::allocate_frame_memory(n * sizeof(T)));
      capacity_ = n;
    }
    size_ = n;
  }

  UninitializedArray() = default;
  UninitializedArray(UninitializedArray&& o) noexcept
      : data_(std::exchange(o.data_, nullptr)), size_(std::exchange(o.size_, 0)),
        capacity_(std::exchange(o.capacity_, 0)) {}
  UninitializedArray& operator=(UninitializedArray&& o) noexcept {
    if (this != &o) {
      release();
      data_ = std::exchange(o.data_, nullptr);
      size_ = std::exchange(o.size_, 0);
      capacity_ = std::exchange(o.capacity_, 0);
    }
    return *this;
  }
  UninitializedArray(const UninitializedArray&) = delete;
  UninitializedArray& operator=(const UninitializedArray&) = delete;
  ~UninitializedArray() { release(); }

  std::size_t size() const { return size_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }

 private:
  void release() {
    detail::free_frame_memory(data_, capacity_ * sizeof(T));
    data_ = nullptr;
    size_ = capacity_ = 0;
  }

  T* data_ = nullptr;
  std::size_t size_ = 0, capacity_ = 0;
};

}  // namespace farm
