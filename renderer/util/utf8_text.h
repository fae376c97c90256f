#pragma once
// UTF-8 text from input, made safe for wherever valid UTF-8 is required (a JSON dump, a proto
// string, a PostgreSQL text value, a terminal): cut without splitting a sequence, and checked.
#include <cstddef>
#include <string>

namespace farm {

// The longest start of `text` of at most `max_bytes` bytes that ends on a character boundary.
std::string utf8_prefix(const std::string& text, std::size_t max_bytes);

// The bytes of the well-formed UTF-8 character that starts at `text[i]`; 0 when none does there
// (a stray continuation byte, a sequence cut short, an overlong form, a surrogate, a code point
// past U+10FFFF). A NUL byte is a well-formed character of 1 byte.
std::size_t utf8_character_bytes(const std::string& text, std::size_t i);

// Whether all of `text` is well-formed UTF-8.
bool is_utf8(const std::string& text);

}  // namespace farm
