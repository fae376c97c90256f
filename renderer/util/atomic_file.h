#pragma once
// Files written whole or not at all (docs/architecture.md, "Files on disk"): a temporary file is
// written beside the target, then renamed over it, so that a crash or a full disk never leaves a
// half-written image, report, tile result or download where a reader would take it for the
// finished one. Every writer of such a file goes through here.
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string_view>

namespace farm {

// Creates the parent folders, calls `write(temp_path)` with a temporary path in the same folder
// (a dot file, which keeps the target's extension: image libraries pick the format by it), then
// renames it onto `target`. The temporary file is removed if `write` or the rename throws.
void write_file_atomically(const std::filesystem::path& target,
                           const std::function<void(const std::filesystem::path&)>& write);

// The same for writers that take an open file (libpng, libjpeg): `write(out)` writes to the
// temporary file, opened "wb". Errors opening or closing it (the last buffered bytes may only
// fail there, e.g. on a full disk) throw std::system_error with the errno, naming `target`.
void write_c_file_atomically(const std::filesystem::path& target, const std::function<void(std::FILE*)>& write);

// `bytes` as the whole of `target`; std::system_error with the errno (ENOSPC kept) naming it.
void write_text_atomically(const std::filesystem::path& target, std::string_view bytes);

// A copy of `from` as the whole of `to`; std::filesystem::filesystem_error when `from` cannot be
// read.
void copy_file_atomically(const std::filesystem::path& from, const std::filesystem::path& to);

}  // namespace farm
