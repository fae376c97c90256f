#pragma once
// zlib streams as the frame writers make them (the EXR's chunks, the PNG's strips): the deflate
// itself is zlib's, raw, on a stream each thread keeps; the checksum is libdeflate's adler32.
// zlib's own adler32 is a byte at a time: it was a fifth of compress2's time on a frame's EXR
// chunks (0.74 of 3.6 ms for a 640x480 frame), libdeflate's vectorised one a fiftieth.
// zlib_compress's bytes are exactly compress2's: the same header, deflate and checksum.
//
// A stream may also be made of pieces deflated apart, on different threads (the PNG's strips):
// each piece but the last ends in a sync flush, so that the next, started with an empty window,
// continues the stream; the pieces' checksums are joined by zlib's adler32_combine.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace farm {

// The two bytes that open a zlib stream deflated at `level` with a 32 KiB window (RFC 1950).
std::array<std::uint8_t, 2> zlib_header(int level);

// Appends the raw deflate of `data` at `level` to `out`: the stream's final block when `last`,
// else a sync flush. Returns false, with `out` as it was, when that would take more than `limit`
// bytes. `run_length`: matches only of the bytes just before (zlib's Z_RLE), which on a PNG's
// filtered rows was 3% faster and 7% smaller than zlib's default search at level 1.
bool deflate_piece(std::span<const std::uint8_t> data, int level, bool last, std::vector<std::uint8_t>& out,
                   std::size_t limit, bool run_length = false);

// Room enough for any deflated piece of `bytes` bytes, flushed or final.
std::size_t deflate_limit(std::size_t bytes);

// Adler-32 of `data` continued from `adler` (1 for a fresh stream).
std::uint32_t adler32_of(std::span<const std::uint8_t> data, std::uint32_t adler = 1);
// The Adler-32 of two pieces one after the other, from each piece's and the second's length.
std::uint32_t adler32_join(std::uint32_t first, std::uint32_t second, std::size_t second_bytes);

// CRC-32 (the PNG chunks' check) of `data` continued from `crc` (0 for a fresh one).
std::uint32_t crc32_of(std::span<const std::uint8_t> data, std::uint32_t crc = 0);

// `value` as four bytes, most significant first, appended to `out` (zlib's and PNG's order).
void append_big_endian(std::uint32_t value, std::vector<std::uint8_t>& out);

// compress2's output for `data` at `level`, or false (`out` cleared) when longer than `limit`.
bool zlib_compress(std::span<const std::uint8_t> data, int level, std::vector<std::uint8_t>& out,
                   std::size_t limit);

}  // namespace farm
