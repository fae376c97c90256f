#pragma once
// Which channel of the new image holds each channel of the reference, matched by name (EXR
// channel order is not part of an image's identity).
#include <cstring>
#include <vector>

#include "renderer/compare/image.h"

namespace farm {

// For each channel of `reference`, its index in `test`; the caller has checked both hold the
// same set of names.
inline std::vector<int> matching_channels(const Image& reference, const Image& test) {
  std::vector<int> in_test(reference.channel_count());
  for (std::size_t c = 0; c < in_test.size(); ++c) in_test[c] = test.channel(reference.channels[c]);
  return in_test;
}

}  // namespace farm
