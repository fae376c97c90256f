#pragma once
// OpenEXR files of a film: R G B A, plus the AOV layers Z, N.X N.Y N.Z, albedo.R albedo.G
// albedo.B, bvh_cost and variance.R variance.G variance.B, named so any EXR tool finds them.
#include <filesystem>
#include <functional>

#include "renderer/image/tile_buffer.h"

namespace farm {

enum class ExrPixelType { Half, Float };

// Colour, normal and albedo are stored as `type` (half by default); depth, bvh_cost and variance
// are always 32-bit float, since half would quantise depth to ~3 significant digits and flush the
// tiny variances of a converged render to zero (half's smallest normal is 6e-5). Writes to a temporary
// file and renames it into place, so a failed write never leaves a truncated image behind.
// `lines_packed(y0, y1)`, when given, is called for each chunk's lines (counted from the image's
// top) on the thread that packed them, as soon as they are: work on the same lines while they are
// in that core's cache (StreamedPreview). The chunks are packed on `threads` threads (0: one a core).
void write_exr(const TileBuffer& image, const std::filesystem::path& file,
               ExrPixelType type = ExrPixelType::Half,
               const std::function<void(int y0, int y1)>& lines_packed = {}, int threads = 0);

// Reads an EXR written by write_exr (or any EXR with those channel names) as floats. The buffer's
// rect is the file's data window; AOVs are present when their channels are.
TileBuffer read_exr(const std::filesystem::path& file);

}  // namespace farm
