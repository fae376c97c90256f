#pragma once
// The files a model file reads besides itself, so a job sent to a farm carries everything its
// loaders will open: an OBJ's material libraries (and the maps they name), a glTF's external
// buffers and images, a COLLADA file's images. References to files that do not exist are left
// out: the loaders treat those the same way on every machine.
#include <filesystem>
#include <vector>

namespace farm {

// Absolute, normalised paths of the existing files `model` references (not `model` itself),
// without duplicates. Throws InputError naming the model when it cannot be read.
std::vector<std::filesystem::path> model_dependencies(const std::filesystem::path& model);

}  // namespace farm
