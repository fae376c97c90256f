#pragma once
// Which of a pixel's samples a buffer holds: the global sample indices [begin, end) within each
// pixel (the index the counter-based sampler is keyed by), the same range for every pixel of a
// render. A frame rendered in sample passes is the concatenation of its passes' ranges.
namespace farm {

struct SampleRange {
  int begin = 0;
  int end = 0;

  int count() const { return end - begin; }
  bool empty() const { return end <= begin; }
  bool operator==(const SampleRange&) const = default;
};

}  // namespace farm
