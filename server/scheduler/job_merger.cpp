#include "server/scheduler/job_merger.h"

#include "renderer/image/output_file.h"
#include "renderer/image/preview.h"

namespace farm {

namespace fs = std::filesystem;

void write_merged(const TileBuffer& film, const MergedFiles& files, ExrPixelType type) {
  write_exr(film, files.exr, type);
  if (files.preview.empty()) return;
  // write_preview has no temp+rename of its own.
  write_file_atomically(files.preview, [&](const fs::path& temp) { write_preview(film, temp); });
}

}  // namespace farm
