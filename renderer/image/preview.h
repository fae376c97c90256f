#pragma once
// 8-bit previews (PNG or JPEG, chosen by extension) of a linear film: RGB clamped to [0, 1] and
// sRGB-encoded.
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <vector>

#include "renderer/image/rgb8_image.h"
#include "renderer/image/tile_buffer.h"

namespace farm {

float linear_to_srgb(float linear);      // the sRGB transfer function, input clamped to [0, 1]
std::uint8_t to_srgb8(float linear);        // rounded to 8 bits: what previews hold

// The film's RGB as a preview holds it: every channel through to_srgb8, rows top to bottom.
Rgb8Image to_srgb8_image(const TileBuffer& image);

// Writes to a temporary file beside `file` and renames it into place. Errors name `file`.
void write_preview(const TileBuffer& image, const std::filesystem::path& file);

// A film's preview made while the film's EXR is written (write_merged): the threads that pack
// the EXR's chunks convert each chunk's rows from the lines they have just read, and write()
// encodes the rows in order as they become ready, on a thread of its own. Converted apart, the
// film was read a second time from another core's cache: 2 to 4 ms of a 640x480 frame's 6.
class StreamedPreview {
 public:
  explicit StreamedPreview(const TileBuffer& film);  // the film outlives it
  // Rows [y0, y1), counted from the film's top; each row once, from any thread.
  void convert(int y0, int y1);
  // No more rows will come (the EXR failed): write() stops waiting and throws.
  void abandon();
  // write_preview's file and errors, each row written as soon as it is converted.
  void write(const std::filesystem::path& file);

 private:
  const TileBuffer& film_;
  Rgb8Image image_;
  std::mutex mutex_;  // guards the three below
  std::condition_variable row_ready_;
  std::vector<bool> ready_;
  int leading_ = 0;  // rows [0, leading_) are all ready
  bool abandoned_ = false;
};

// True for the extensions write_preview knows, in any case: .png; .jpg .jpeg .jpe .jif .jfif .jfi
// (checked before a long render starts).
bool preview_format_supported(const std::filesystem::path& file);

}  // namespace farm
