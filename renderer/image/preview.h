#pragma once
// 8-bit previews (PNG or JPEG, chosen by extension) of a linear film: RGB clamped to [0, 1] and
// sRGB-encoded.
#include <condition_variable>
#include <exception>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "renderer/image/png_strips.h"
#include "renderer/image/rgb8_image.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/util/uninitialized_array.h"

namespace farm {

float linear_to_srgb(float linear);      // the sRGB transfer function, input clamped to [0, 1]
std::uint8_t to_srgb8(float linear);        // rounded to 8 bits: what previews hold

// Which code encodes a preview's channels: AVX2 where the CPU has it (Best), or the one every
// x86-64 runs. Both give to_srgb8's bytes; tests compare them.
enum class Srgb8Encoder { Best, Portable };

// The film's RGB as a preview holds it: every channel through to_srgb8, rows top to bottom.
Rgb8Image to_srgb8_image(const TileBuffer& image, Srgb8Encoder encoder = Srgb8Encoder::Best);

// Writes to a temporary file beside `file` and renames it into place. Errors name `file`.
void write_preview(const TileBuffer& image, const std::filesystem::path& file);

// A film's preview made while the film's EXR is written (write_merged): the threads that pack
// the EXR's chunks convert each chunk's rows from the lines they have just read (converted apart,
// the film was read a second time from another core's cache: 2 to 4 ms of a 640x480 frame's 6).
// A PNG's strips are compressed there too, by the thread that completes their rows (png_strips.h),
// and finish() only writes the file; a JPEG is encoded row by row, in order, as the rows become
// ready, on a thread of its own.
class StreamedPreview {
 public:
  // `file`'s extension picks the format (write_preview's, and its errors). The film outlives this.
  StreamedPreview(const TileBuffer& film, std::filesystem::path file);
  ~StreamedPreview();  // abandons a preview not finished
  StreamedPreview(const StreamedPreview&) = delete;
  StreamedPreview& operator=(const StreamedPreview&) = delete;

  // Rows [y0, y1), counted from the film's top; each row once, from any thread.
  void convert(int y0, int y1);
  // No more rows will come (the EXR failed): finish() stops waiting and throws, leaving no file.
  void abandon();
  // Once every row has come (it waits for them): the file, written as write_preview writes it.
  void finish();

 private:
  const std::uint8_t* row(int y) const;        // row y of pixels_
  std::runtime_error rows_never_came() const;  // what finish() throws once abandoned

  const TileBuffer& film_;
  const std::filesystem::path file_;
  const bool png_;
  const int width_;
  const int height_;
  UninitializedArray<std::uint8_t> pixels_;  // the film's rows as sRGB bytes, as they are converted
  std::optional<PngStrips> strips_;  // PNG
  std::thread jpeg_encoder_;         // JPEG
  std::exception_ptr jpeg_failure_;  // set by the encoder before it ends
  mutable std::mutex mutex_;         // guards the five below
  std::condition_variable changed_;
  std::vector<int> strip_rows_ready_;  // PNG: per strip, its rows converted
  int strips_done_ = 0;                // PNG: strips compressed
  std::exception_ptr strip_failure_;   // PNG: the first strip that failed
  int leading_ = 0;                    // JPEG: rows [0, leading_) are all converted
  std::vector<bool> ready_;            // JPEG: per row, converted
  bool abandoned_ = false;
};

// True for the extensions write_preview knows, in any case: .png; .jpg .jpeg .jpe .jif .jfif .jfi
// (checked before a long render starts).
bool preview_format_supported(const std::filesystem::path& file);

}  // namespace farm
