#pragma once
// An 8-bit RGB PNG, marked sRGB, written here rather than through libpng so that its pixels can
// be compressed in strips of 16 rows, each strip on its own: on any thread, in any order (the
// frame writers compress a strip on the thread that has just converted its rows, beside the EXR's
// chunk of the same lines), joined into the file's one zlib stream at the end
// (zlib_stream.h: each strip a piece of the stream, their checksums joined). libpng compressed a
// 1080p preview on one thread, after the EXR, with zlib's byte-at-a-time checksum.
//
// The file, as the PNG specification (ISO/IEC 15948) lays it out: the signature; IHDR (8-bit RGB,
// not interlaced); sRGB, gAMA and cHRM saying the values are sRGB-encoded, as libpng's
// png_set_sRGB_gAMA_and_cHRM wrote them; one IDAT chunk a strip (the first opening with the zlib
// header, the last closing with the checksum); IEND. Every row is filtered "up" (its difference
// to the row above) but a strip's first, filtered "sub" (to the pixel on its left), which needs
// no row of another strip. Deflated by igzip at its level 1 (zlib_stream.h): speed before size,
// as before (a 512x512 Cornell box preview 21 ms instead of 40 at libpng's defaults); the 1080p
// cow grid's preview 516,731 bytes with zlib's level 1 and run-length matches, 481,246 with igzip.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <vector>

namespace farm {

class PngStrips {
 public:
  static constexpr int kRows = 16;

  // Throws std::runtime_error naming `name` for an image without pixels.
  PngStrips(int width, int height, const std::filesystem::path& name);

  int strips() const { return static_cast<int>(strips_.size()); }
  // The first row of strip k and the row after its last.
  int first_row(int strip) const { return strip * kRows; }
  int end_row(int strip) const;

  // Filters and compresses strip k from its rows, row(y) giving row y's width x RGB bytes. Each
  // strip once; different strips from any threads at the same time.
  void compress(int strip, const std::function<const std::uint8_t*(int y)>& row);

  // The file, every strip compressed. A failed write throws std::system_error with its errno
  // (ENOSPC for a full disk), any other failure std::runtime_error; both name `name`.
  void write(std::FILE* out) const;

 private:
  struct Strip {
    std::vector<std::uint8_t> deflated;  // the first strip's opens with the zlib header
    std::uint32_t adler = 1;             // of the strip's filtered rows
    std::size_t filtered_bytes = 0;
  };

  int width_;
  int height_;
  std::filesystem::path name_;
  std::vector<Strip> strips_;
};

}  // namespace farm
