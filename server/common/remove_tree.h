#pragma once
// A folder and everything in it removed, saying how much room that gave back: a deleted job's
// files (`farm delete`, the scheduler's --keep-finished).
#include <cstdint>
#include <filesystem>

namespace farm {

// Removes `dir` (nothing when it is absent); returns the bytes of the regular files that were in
// it. std::filesystem::filesystem_error when something in it cannot be removed.
std::uintmax_t remove_tree(const std::filesystem::path& dir);

}  // namespace farm
