#include "renderer/image/zlib_stream.h"

#include <libdeflate.h>
#include <zlib.h>

#include <algorithm>
#include <stdexcept>

#include "renderer/util/uninitialized_array.h"

namespace farm {
namespace {

// Each thread's raw deflate stream, reset between pieces: a fresh one allocates and first
// touches about 270 KiB of window and hash tables, which compress2 did for every chunk.
class ThreadDeflater {
 public:
  ThreadDeflater() = default;
  ThreadDeflater(const ThreadDeflater&) = delete;
  ThreadDeflater& operator=(const ThreadDeflater&) = delete;
  ~ThreadDeflater() {
    if (open_) deflateEnd(&stream_);
  }

  z_stream& fresh(int level, int strategy) {
    if (open_ && level == level_ && strategy == strategy_) {
      deflateReset(&stream_);
      return stream_;
    }
    if (open_) deflateEnd(&stream_);
    open_ = false;
    stream_ = z_stream{};
    // compress2's window (15 bits) and memory level (8), without its header and checksum.
    if (deflateInit2(&stream_, level, Z_DEFLATED, -15, 8, strategy) != Z_OK) {
      throw std::runtime_error("zlib could not start a deflate stream");
    }
    open_ = true;
    level_ = level;
    strategy_ = strategy;
    return stream_;
  }

 private:
  z_stream stream_{};
  bool open_ = false;
  int level_ = 0;
  int strategy_ = Z_DEFAULT_STRATEGY;
};

}  // namespace

std::array<std::uint8_t, 2> zlib_header(int level) {
  if (level == Z_DEFAULT_COMPRESSION) level = 6;
  // RFC 1950: CMF says deflate with a 32 KiB window; FLG's top bits the speed the level chose
  // (as zlib sets them), its low five bits make the two bytes a multiple of 31.
  const unsigned speed = level < 2 ? 0 : level < 6 ? 1 : level == 6 ? 2 : 3;
  unsigned header = (0x78u << 8) | (speed << 6);
  header += 31 - header % 31;
  return {static_cast<std::uint8_t>(header >> 8), static_cast<std::uint8_t>(header & 0xFF)};
}

bool deflate_piece(std::span<const std::uint8_t> data, int level, bool last, std::vector<std::uint8_t>& out,
                   std::size_t limit, bool run_length) {
  thread_local ThreadDeflater deflater;
  // Deflated into room this thread keeps (never zeroed, no fresh pages), then only the bytes
  // made are appended.
  thread_local UninitializedArray<std::uint8_t> room;
  z_stream& stream = deflater.fresh(level, run_length ? Z_RLE : Z_DEFAULT_STRATEGY);
  room.allocate(std::max<std::size_t>(limit, 1));
  stream.next_out = room.begin();
  stream.avail_out = static_cast<uInt>(std::min<std::size_t>(limit, 0xFFFFFFFFu));
  const std::uint8_t* next = data.data();
  std::size_t left = data.size();
  bool fits = true;
  do {
    // avail_in is 32 bits: a larger piece goes in parts.
    const std::size_t part = std::min<std::size_t>(left, std::size_t{1} << 30);
    stream.next_in = const_cast<Bytef*>(next);
    stream.avail_in = static_cast<uInt>(part);
    next += part;
    left -= part;
    const int flush = left > 0 ? Z_NO_FLUSH : last ? Z_FINISH : Z_SYNC_FLUSH;
    const int status = deflate(&stream, flush);
    // Out of room shows as avail_out 0 (a flush not finished) or Z_OK where Z_FINISH wanted the end.
    if (status == Z_STREAM_ERROR || stream.avail_out == 0 || (flush == Z_FINISH && status != Z_STREAM_END)) {
      fits = false;
    }
  } while (fits && left > 0);
  if (fits) out.insert(out.end(), room.begin(), stream.next_out);
  return fits;
}

std::size_t deflate_limit(std::size_t bytes) {
  // compressBound covers the zlib wrapper's six bytes; a sync flush adds at most five.
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

bool zlib_compress(std::span<const std::uint8_t> data, int level, std::vector<std::uint8_t>& out,
                   std::size_t limit) {
  out.clear();
  if (limit < 6) return false;
  const std::array<std::uint8_t, 2> header = zlib_header(level);
  out.assign(header.begin(), header.end());
  if (!deflate_piece(data, level, true, out, limit - 6)) {
    out.clear();
    return false;
  }
  append_big_endian(adler32_of(data), out);
  return true;
}

}  // namespace farm
