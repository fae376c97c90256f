#pragma once
// The one rule for "this file lies inside that folder", wherever a path from outside must stay
// within a root. Files named by a job or a model go through confine_file (confined_file.h), which
// builds on this; suites and rubrics use it for their own files. Paths are resolved first
// (weakly_canonical: `..` and every symlink along the existing part of the path), so neither
// `..` nor a symlink leads out; folders compare component-wise, so /assets2 is not inside /assets.
#include <filesystem>
#include <optional>

namespace farm {

// Both already resolved (weakly_canonical): true when `path` is `root` or lies below it.
bool lies_within(const std::filesystem::path& resolved_root, const std::filesystem::path& resolved_path);

// `path` resolved, when it lies within `resolved_root`; nullopt when it does not or cannot be
// resolved.
std::optional<std::filesystem::path> resolve_within(const std::filesystem::path& resolved_root,
                                                    const std::filesystem::path& path);

}  // namespace farm
