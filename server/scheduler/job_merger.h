#pragma once
// A job's finished tiles -> its frame: every result file (one per batch of tiles) pasted into one
// TileBuffer, written as the EXR (R G B A plus the job's AOV layers) and the sRGB PNG preview, as
// `farm render` writes them.
#include <filesystem>
#include <string>
#include <vector>

#include "renderer/image/exr_io.h"
#include "renderer/image/tile_buffer.h"
#include "server/scheduler/tile_results.h"

namespace farm {

struct MergeRequest {
  std::string job_id;
  Rect image;                     // {0, 0, width, height}
  AovSet aovs;
  std::vector<std::uint32_t> parts;  // the job's result files (TileResults), each once
};

struct MergedFrame {
  TileBuffer film;                // stats summed over the tiles
};

// Reads and pastes every part; std::runtime_error when one is missing or does not fit the image.
MergedFrame merge_tiles(const TileResults& results, const MergeRequest& request);

struct MergedFiles {
  std::filesystem::path exr, preview;
};

// Writes <dir>/<stem>.exr (`type`) and <dir>/<stem>.png, each atomically.
MergedFiles write_merged(const TileBuffer& film, const std::filesystem::path& dir,
                         const std::string& stem, ExrPixelType type = ExrPixelType::Half);

}  // namespace farm
