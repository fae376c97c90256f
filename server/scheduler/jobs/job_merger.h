#pragma once
// A job's merged frame (FrameAssembly::assemble) -> its files: the EXR (R G B A plus the job's AOV
// layers) and the sRGB preview, each written atomically, as `farm render` writes them.
#include <filesystem>
#include <string>
#include <vector>

#include "renderer/image/exr_io.h"
#include "renderer/image/tile_buffer.h"

namespace farm {

struct MergedFiles {
  std::filesystem::path exr, preview;
};

// Writes files.exr (`type`) and, unless it is empty, files.preview, each atomically, on `threads`
// threads (0: one a core). DiskFull (naming the EXR's folder) when the disk has no room for them.
void write_merged(const TileBuffer& film, const MergedFiles& files, ExrPixelType type = ExrPixelType::Half,
                  int threads = 0);

}  // namespace farm
