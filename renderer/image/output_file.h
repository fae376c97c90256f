#pragma once
// Writing result files so that a crash or a full disk never leaves a half-written image where
// the finished one should be: write next to the target, then rename over it.
#include <cstdio>
#include <filesystem>
#include <functional>

namespace farm {

// Creates the parent folders, calls `write(temp_path)` with a temporary path in the same folder
// that keeps the target's extension (image libraries pick the format by extension), then renames
// it onto `target`. The temporary file is removed if `write` throws.
void write_file_atomically(const std::filesystem::path& target,
                           const std::function<void(const std::filesystem::path&)>& write);

// The same for writers that take an open file (libpng, libjpeg): `write(out)` writes to the
// temporary file, opened "wb". Errors opening or closing it (the last buffered bytes may only
// fail there, e.g. on a full disk) throw std::system_error with the errno, naming `target`.
void write_c_file_atomically(const std::filesystem::path& target, const std::function<void(std::FILE*)>& write);

}  // namespace farm
