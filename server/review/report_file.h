#pragma once
// The files grading reports write, each atomically (a temporary file beside the target, renamed
// over it), so a crash or a full disk never leaves a half-written page, table or picture where a
// reader would take it for the finished one.
#include <filesystem>
#include <string_view>

namespace farm {

// Writes `text` to `file`, creating the parent folders. Throws std::runtime_error naming the file.
void write_report_text(const std::filesystem::path& file, std::string_view text);

// Copies `from` to `to` (replacing it), creating the parent folders. Throws
// std::filesystem::filesystem_error when `from` cannot be read.
void copy_report_file(const std::filesystem::path& from, const std::filesystem::path& to);

}  // namespace farm
