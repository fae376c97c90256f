#pragma once
// What regression suites and grading rubrics read alike: a bounded JSON file, names that become
// file names, and paths relative to the file that must exist.
#include <filesystem>
#include <optional>
#include <string>

#include "renderer/util/json_reader.h"

namespace farm {

// The text of a suite or rubric file (a regular file of at most 4 MiB); InputError otherwise.
std::string read_bounded_text(const std::filesystem::path& file);

// Letters, digits, '-', '_' and '.', at most 100, not "." or "..": safe as one file name.
bool is_safe_name(const std::string& name);

// A path relative to `folder` (or absolute), made absolute and normal.
std::filesystem::path resolve_from(const std::filesystem::path& folder, const std::string& text);

// An existing folder named by `value` (relative to `folder`); `folder` itself when absent.
std::filesystem::path read_folder(const std::optional<JsonValue>& value, const std::filesystem::path& folder);

// An existing job file named by `value`, relative to `folder`.
std::filesystem::path read_job_path(const JsonValue& value, const std::filesystem::path& folder);

}  // namespace farm
