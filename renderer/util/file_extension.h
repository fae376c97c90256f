#pragma once
// A file's extension as the farm matches it: lower case, so that COW.DAE, Turntable.MP4 and
// frame.PNG are read as what they are.
#include <filesystem>
#include <string>

namespace farm {

// `file`'s extension with its dot, in lower case ASCII (".dae"); empty when it has none.
std::string lowercase_extension(const std::filesystem::path& file);

}  // namespace farm
