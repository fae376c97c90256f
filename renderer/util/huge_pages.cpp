#include "renderer/util/huge_pages.h"

#include <sys/mman.h>

#include <cstdlib>

namespace farm {
namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
constexpr std::size_t kPage = 4096;

std::size_t alignment_for(std::size_t bytes) { return bytes >= 2 * kHugePage ? kHugePage : kPage; }

}  // namespace

std::size_t large_array_size(std::size_t bytes) {
  const std::size_t a = alignment_for(bytes);
  if (bytes > std::numeric_limits<std::size_t>::max() - a) throw std::bad_alloc();
  return (bytes + a - 1) / a * a;
}

void* allocate_large_array(std::size_t bytes) {
  if (bytes == 0) bytes = 1;
  const std::size_t rounded = large_array_size(bytes);
  void* p = std::aligned_alloc(alignment_for(bytes), rounded);
  if (!p) throw std::bad_alloc();
  if (alignment_for(bytes) == kHugePage) madvise(p, rounded, MADV_HUGEPAGE);
  return p;
}

void free_large_array(void* p) noexcept { std::free(p); }

}  // namespace farm
