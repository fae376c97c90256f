#pragma once
// Text cut to a length in bytes without splitting a UTF-8 sequence, so that what is left is still
// valid wherever valid UTF-8 is required (a JSON dump, a proto string, a terminal).
#include <cstddef>
#include <string>

namespace farm {

// The longest start of `text` of at most `max_bytes` bytes that ends on a character boundary.
std::string utf8_prefix(const std::string& text, std::size_t max_bytes);

}  // namespace farm
