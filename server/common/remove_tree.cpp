#include "server/common/remove_tree.h"

namespace farm {

namespace fs = std::filesystem;

std::uintmax_t remove_tree(const fs::path& dir) {
  std::uintmax_t bytes = 0;
  std::error_code ec;
  // Links are not followed: only what is in the folder itself is counted and removed.
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code size_ec;
    if (it->is_regular_file(size_ec) && !it->is_symlink(size_ec)) bytes += it->file_size(size_ec);
  }
  fs::remove_all(dir);  // throws filesystem_error; absent is no error
  return bytes;
}

}  // namespace farm
