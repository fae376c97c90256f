#pragma once
// Counting the whitespace-separated tokens of a text, as the COLLADA check does for a mesh's arrays
// and index lists (collada_check.cpp): they are most of a COLLADA file, and a byte-at-a-time loop
// over them was a tenth of the bunny's load.
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace farm {

struct Tokens {
  std::uint64_t count = 0;
  std::size_t bad = 0;  // with digits_only: the first byte neither space nor digit; text.size() if none
};

// Tokens are separated by ' ', '\t', '\n' and '\r'. With `digits_only` the count stops at the
// first byte that is neither a space nor a digit ('0' to '9'), which `bad` then gives.
Tokens count_tokens(std::string_view text, bool digits_only);

}  // namespace farm
