#include "server/common/plain_file_name.h"

#include <algorithm>

namespace farm {

std::string plain_file_name(std::string_view name, std::string_view fallback) {
  std::string plain(name.substr(0, 255));  // a longer name no file system takes
  for (char& c : plain) {
    const bool kept = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                      c == '-' || c == '_';
    if (!kept) c = '_';
  }
  if (std::all_of(plain.begin(), plain.end(), [](char c) { return c == '.'; })) return std::string(fallback);
  // Nor hidden: "../x" (made ".._x") would be a dot file nobody sees in a listing.
  for (std::size_t i = 0; i < plain.size() && plain[i] == '.'; ++i) plain[i] = '_';
  return plain;
}

}  // namespace farm
