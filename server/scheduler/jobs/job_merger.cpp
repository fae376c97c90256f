#include "server/scheduler/jobs/job_merger.h"

#include <future>

#include "renderer/image/preview.h"
#include "server/common/disk_full.h"

namespace farm {

void write_merged(const TileBuffer& film, const MergedFiles& files, ExrPixelType type) {
  // The preview's rows are converted by the threads packing the EXR's chunks, from the lines they
  // have just read, and encoded on a thread of its own as they come (StreamedPreview): zlib
  // makes each file a few tens of milliseconds for a 1080p frame, and the farm waits for both.
  try {
    if (files.preview.empty()) {
      write_exr(film, files.exr, type);
      return;
    }
    StreamedPreview preview(film);
    std::future<void> written = std::async(std::launch::async, [&] { preview.write(files.preview); });
    try {
      write_exr(film, files.exr, type, [&](int y0, int y1) { preview.convert(y0, y1); });
    } catch (...) {
      preview.abandon();  // the future's destructor then waits for a thread that stops
      throw;
    }
    written.get();
  } catch (const std::exception&) {
    rethrow_as_disk_full(files.exr.parent_path());
  }
}

}  // namespace farm
