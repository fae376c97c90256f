#pragma once
// One chunk of an OpenEXR scanline file in ZIP compression, packed here (exr_io.cpp writes the
// file around the chunks through OpenEXRCore). OpenEXR's C++ writer copies each channel through a
// generic frame buffer, then reorders the bytes, then compresses: for a 640x480 half RGBA frame
// that was 7 ms of the 11 ms a frame's files took, and the frame path's largest cost beside the
// engine. Here each line's floats are converted (float_to_half.h) straight into the two halves of
// the reorder, and the predictor is one pass.
//
// The format, as OpenEXR's file layout defines it: a chunk holds 16 lines (fewer at the bottom of
// the image); each line holds every channel in the file's channel order (sorted by name), each
// channel's values for the line's pixels, little-endian. The bytes are then split into two
// halves, the bytes at even offsets followed by those at odd offsets; each byte after the first is
// replaced by its difference to the one before plus 128 (mod 256); and the result is compressed
// as one zlib stream (any deflate will do: ours is igzip's, zlib_stream.h, and the inflated
// bytes are those of OpenEXR's own writer). A chunk that deflate would not make smaller is
// stored as it was before the split, which is how a reader tells the two apart (its size equals
// the unpacked size).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace farm {

inline constexpr int kExrZipLines = 16;

// One channel of the image being written, as it lies in memory.
struct ExrChannel {
  std::string name;
  bool half = true;             // stored as HALF (converted), else as FLOAT (copied)
  const char* first = nullptr;  // the value at the image's top-left pixel (a float)
  std::size_t stride = 0;       // bytes from one pixel to the next
  std::size_t row_stride = 0;   // bytes from one line to the next
};

// Bytes of one line of `width` pixels of these channels, unpacked.
std::size_t exr_line_bytes(const std::vector<ExrChannel>& channels, int width);

// The chunk of lines [y0, y1) (counted from the image's first line) of `width` pixels, channels
// in the file's order, as a zlib stream (zlib_stream.h), or unpacked when that is not smaller.
std::vector<std::uint8_t> pack_zip_chunk(const std::vector<ExrChannel>& channels, int width, int y0, int y1);

}  // namespace farm
