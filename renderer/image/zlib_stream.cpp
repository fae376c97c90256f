#include "renderer/image/zlib_stream.h"

#include <isa-l/igzip_lib.h>
#include <libdeflate.h>
#include <zlib.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "renderer/util/uninitialized_array.h"

namespace farm {
namespace {

// What a thread keeps for igzip: its stream state (80 KiB), level 1's hash tables and token
// buffer (276 KiB), and the room a piece is deflated into (never zeroed), so that a piece costs
// no allocation and no fresh pages; only the bytes made are appended to the caller's vector.
struct ThreadIgzip {
  std::unique_ptr<isal_zstream> stream = std::make_unique<isal_zstream>();
  UninitializedArray<std::uint8_t> level_buffer;
  UninitializedArray<std::uint8_t> room;
  ThreadIgzip() { level_buffer.allocate(ISAL_DEF_LVL1_DEFAULT); }
};

}  // namespace

std::array<std::uint8_t, 2> zlib_header() {
  // CMF: deflate with a 32 KiB window (0x78). FLG: the level field says "fastest" (0, as zlib
  // marks its levels 0 and 1), and the low five bits make the two bytes a multiple of 31.
  unsigned header = 0x78u << 8;
  header += 31 - header % 31;
  return {static_cast<std::uint8_t>(header >> 8), static_cast<std::uint8_t>(header & 0xFF)};
}

bool deflate_piece(std::span<const std::uint8_t> data, bool last, std::vector<std::uint8_t>& out, std::size_t limit) {
  if (data.size() > std::numeric_limits<std::uint32_t>::max()) return false;  // no frame's piece is near it
  thread_local ThreadIgzip igzip;
  UninitializedArray<std::uint8_t>& room = igzip.room;
  room.allocate(std::max<std::size_t>(limit, 1));
  isal_zstream& stream = *igzip.stream;
  isal_deflate_stateless_init(&stream);
  stream.level = 1;
  stream.level_buf = igzip.level_buffer.begin();
  stream.level_buf_size = static_cast<std::uint32_t>(igzip.level_buffer.size());
  stream.gzip_flag = IGZIP_DEFLATE;  // raw: the caller writes the wrapper
  // A piece but the last ends byte-aligned in a block that is not final (igzip's full flush),
  // so that the next piece's blocks follow it in the same stream.
  stream.end_of_stream = last ? 1 : 0;
  stream.flush = last ? NO_FLUSH : FULL_FLUSH;
  stream.next_in = const_cast<std::uint8_t*>(data.data());
  stream.avail_in = static_cast<std::uint32_t>(data.size());
  stream.next_out = room.begin();
  stream.avail_out = static_cast<std::uint32_t>(std::min<std::size_t>(limit, std::numeric_limits<std::uint32_t>::max()));
  const int status = isal_deflate_stateless(&stream);
  if (status == STATELESS_OVERFLOW) return false;
  if (status != COMP_OK) throw std::runtime_error("igzip could not deflate (error " + std::to_string(status) + ")");
  out.insert(out.end(), room.begin(), stream.next_out);
  return true;
}

std::size_t deflate_limit(std::size_t bytes) {
  // compressBound covers the zlib wrapper's six bytes and more than igzip's stored blocks add (five
  // bytes each 64 KiB); a piece's closing flush adds at most five.
  return static_cast<std::size_t>(compressBound(static_cast<uLong>(bytes))) + 16;
}

// libdeflate, as zlib, answers a null buffer with the initial value: an empty span (whose data()
// may be null) continues the checksum instead.
std::uint32_t adler32_of(std::span<const std::uint8_t> data, std::uint32_t adler) {
  return data.empty() ? adler : libdeflate_adler32(adler, data.data(), data.size());
}

std::uint32_t adler32_join(std::uint32_t first, std::uint32_t second, std::size_t second_bytes) {
  return static_cast<std::uint32_t>(adler32_combine(first, second, static_cast<z_off_t>(second_bytes)));
}

std::uint32_t crc32_of(std::span<const std::uint8_t> data, std::uint32_t crc) {
  return data.empty() ? crc : libdeflate_crc32(crc, data.data(), data.size());
}

void append_big_endian(std::uint32_t value, std::vector<std::uint8_t>& out) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(value >> shift));
}

bool zlib_compress(std::span<const std::uint8_t> data, std::vector<std::uint8_t>& out, std::size_t limit) {
  out.clear();
  if (limit < 6) return false;
  const std::array<std::uint8_t, 2> header = zlib_header();
  out.assign(header.begin(), header.end());
  if (!deflate_piece(data, true, out, limit - 6)) {
    out.clear();
    return false;
  }
  append_big_endian(adler32_of(data), out);
  return true;
}

}  // namespace farm
