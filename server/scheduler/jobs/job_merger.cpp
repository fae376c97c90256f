#include "server/scheduler/jobs/job_merger.h"

#include <future>

#include "renderer/image/preview.h"
#include "server/common/disk_full.h"

namespace farm {

void write_merged(const TileBuffer& film, const MergedFiles& files, ExrPixelType type) {
  // The preview is encoded and compressed on a thread of its own while the EXR is: zlib makes
  // each a few tens of milliseconds for a 1080p frame, and the farm waits for both.
  try {
    std::future<void> preview;
    if (!files.preview.empty()) {
      preview = std::async(std::launch::async, [&] { write_preview(film, files.preview); });
    }
    write_exr(film, files.exr, type);  // if it throws, the future's destructor waits for the preview
    if (preview.valid()) preview.get();
  } catch (const std::exception&) {
    rethrow_as_disk_full(files.exr.parent_path());
  }
}

}  // namespace farm
