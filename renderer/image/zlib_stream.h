#pragma once
// zlib streams (RFC 1950) as the frame writers make them (the EXR's chunks, the PNG's strips):
// the deflate is Intel ISA-L's igzip at its level 1, raw; the checksum is libdeflate's adler32.
// Measured on a 1920x1080 frame's 68 EXR chunks (16.6 MB): zlib's level 1 took 38 ms and made
// 768,572 bytes, igzip's level 1 6.2 ms and 716,354 bytes. Both checksums were zlib's byte at a
// time, libdeflate's are vectorised. Any inflater reads the streams: OpenEXR, libpng, zlib.
//
// A stream may also be made of pieces deflated apart, on different threads (the PNG's strips):
// each piece but the last ends byte-aligned in a block that is not final, so that the next,
// started with an empty window, continues the stream; the pieces' checksums are joined by zlib's
// adler32_combine.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace farm {

// The two bytes that open a zlib stream with a 32 KiB window, deflated by the fastest method.
std::array<std::uint8_t, 2> zlib_header();

// Appends the raw deflate of `data` to `out`: ending in the stream's final block when `last`,
// else byte-aligned for the next piece. Returns false, with `out` as it was, when that would take
// more than `limit` bytes.
bool deflate_piece(std::span<const std::uint8_t> data, bool last, std::vector<std::uint8_t>& out, std::size_t limit);

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

// The zlib stream of `data` (header, deflate, Adler-32), or false (`out` cleared) when longer than
// `limit` bytes.
bool zlib_compress(std::span<const std::uint8_t> data, std::vector<std::uint8_t>& out, std::size_t limit);

}  // namespace farm
