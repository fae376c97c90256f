#pragma once
// The preview module (oiio_preview_module.cpp), opened the first time a preview is checked or
// written, so that commands that write none (submit, status, worker) start without OpenImageIO.
#include "renderer/image/oiio_preview_module.h"

namespace farm {

struct PreviewWriter {
  FarmPreviewCanWrite can_write = nullptr;
  FarmPreviewWriteRgb8 write_rgb8 = nullptr;
};

// Opens the module once (thread-safe). Looks in $FARM_PREVIEW_MODULE, then beside the running
// executable, then where the build put it; throws std::runtime_error naming each place tried.
const PreviewWriter& preview_writer();

// Starts opening the module on a thread of its own (about 0.3 s) while the caller goes on, e.g.
// loading models; preview_writer() then waits for it. Errors surface there, not here.
void start_loading_preview_writer();

}  // namespace farm
