#include "server/scheduler/jobs/job_merger.h"

#include "renderer/image/preview.h"
#include "server/common/disk_full.h"

namespace farm {

void write_merged(const TileBuffer& film, const MergedFiles& files, ExrPixelType type, int threads) {
  // The preview's rows are converted, and a PNG's strips compressed, by the threads packing the
  // EXR's chunks, from the lines they have just read (StreamedPreview): zlib makes each file a few
  // tens of milliseconds for a 1080p frame, and the farm waits for both.
  try {
    if (files.preview.empty()) {
      write_exr(film, files.exr, type, {}, threads);
      return;
    }
    StreamedPreview preview(film, files.preview);  // if the EXR fails, abandoned unwritten
    write_exr(film, files.exr, type, [&](int y0, int y1) { preview.convert(y0, y1); }, threads);
    preview.finish();
  } catch (const std::exception&) {
    rethrow_as_disk_full(files.exr.parent_path());
  }
}

}  // namespace farm
