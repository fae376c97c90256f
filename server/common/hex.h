#pragma once
// Bytes as lowercase hex and back: the names of content-addressed assets and job ids are written
// so, and the schedulers' relayed events travel so (text channels that take no raw bytes).
#include <optional>
#include <string>
#include <string_view>

namespace farm {

std::string to_hex(std::string_view bytes);
// The bytes of `hex` (lowercase or uppercase digits, two a byte); nullopt for anything else.
std::optional<std::string> from_hex(std::string_view hex);
// Only the digits 0-9 and a-f (the empty text too).
bool is_lowercase_hex(std::string_view text);

}  // namespace farm
