#pragma once
// A file's bytes as one string, for the small files a job names (job text, OBJ/MTL, glTF JSON).
#include <filesystem>
#include <string>
#include <string_view>

namespace farm {

// InputError "<file>: cannot read the <what>" when the file cannot be read.
std::string read_whole_file(const std::filesystem::path& file, std::string_view what);

}  // namespace farm
