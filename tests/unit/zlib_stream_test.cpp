// The frame writers' zlib streams (renderer/image/zlib_stream.h) against zlib itself: streams
// zlib inflates back to the bytes given (checking header and checksum), pieces deflated apart that
// inflate to the whole, and checksums equal to zlib's own.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <random>
#include <vector>

#include "renderer/image/zlib_stream.h"

namespace farm {
namespace {

// Bytes as a frame's chunks hold them: long runs (a background), a ramp, and noise.
std::vector<std::uint8_t> frame_like_bytes(std::size_t n, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::vector<std::uint8_t> bytes(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t part = i * 3 / n;
    bytes[i] = part == 0 ? 128 : part == 1 ? static_cast<std::uint8_t>(i / 7) : static_cast<std::uint8_t>(random());
  }
  return bytes;
}

// zlib's inflate of a whole stream, which checks its header and its Adler-32.
std::vector<std::uint8_t> zlibs_uncompress(const std::vector<std::uint8_t>& stream, std::size_t size) {
  std::vector<std::uint8_t> back(size + 1);
  uLongf got = static_cast<uLongf>(back.size());
  EXPECT_EQ(uncompress(back.data(), &got, stream.data(), static_cast<uLong>(stream.size())), Z_OK);
  back.resize(got);
  return back;
}

TEST(ZlibStream, ZlibInflatesItsStreamBackToTheBytesAndTheFrameLikeOnesShrink) {
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{1000}, std::size_t{81920}, std::size_t{300001},
                        std::size_t{3'000'000}}) {
    const std::vector<std::uint8_t> data = frame_like_bytes(n, static_cast<std::uint32_t>(n) + 7);
    std::vector<std::uint8_t> ours;
    ASSERT_TRUE(zlib_compress(data, ours, compressBound(static_cast<uLong>(n)))) << n;
    EXPECT_EQ(zlibs_uncompress(ours, n), data) << n << " bytes";
    // A third of the bytes is noise: the stream is a little over two thirds of them, no more.
    if (n >= 1000) {
      EXPECT_LT(ours.size(), n * 3 / 4) << n << " bytes";
    }
    // Twice on this thread: its state is started afresh, not carried over.
    std::vector<std::uint8_t> again;
    ASSERT_TRUE(zlib_compress(data, again, compressBound(static_cast<uLong>(n))));
    EXPECT_EQ(again, ours);
  }
}

TEST(ZlibStream, AStreamLongerThanTheLimitIsRefusedAndLeavesNothing) {
  const std::vector<std::uint8_t> noise = [] {
    std::mt19937 random(3);
    std::vector<std::uint8_t> bytes(4096);
    for (std::uint8_t& b : bytes) b = static_cast<std::uint8_t>(random());
    return bytes;
  }();
  std::vector<std::uint8_t> out{1, 2, 3};
  EXPECT_FALSE(zlib_compress(noise, out, noise.size() - 1));  // noise does not shrink
  EXPECT_TRUE(out.empty());
  std::vector<std::uint8_t> piece{9};
  EXPECT_FALSE(deflate_piece(noise, true, piece, 100));
  EXPECT_EQ(piece, std::vector<std::uint8_t>{9});
}

TEST(ZlibStream, PiecesDeflatedApartInflateToTheWholeAndTheirChecksumsJoin) {
  const std::vector<std::uint8_t> data = frame_like_bytes(200000, 11);
  const std::size_t cuts[] = {0, 1, 65536, 65537, 150000, data.size()};
  std::vector<std::uint8_t> stream;
  const auto header = zlib_header();
  stream.assign(header.begin(), header.end());
  std::uint32_t adler = 1;
  for (std::size_t k = 0; k + 1 < std::size(cuts); ++k) {
    const std::span<const std::uint8_t> piece(data.data() + cuts[k], cuts[k + 1] - cuts[k]);
    ASSERT_TRUE(deflate_piece(piece, k + 2 == std::size(cuts), stream, compressBound(200000)));
    adler = adler32_join(adler, adler32_of(piece), piece.size());
  }
  EXPECT_EQ(adler, adler32_of(data));
  EXPECT_EQ(adler, static_cast<std::uint32_t>(adler32(1, data.data(), static_cast<uInt>(data.size()))));
  append_big_endian(adler, stream);
  std::vector<std::uint8_t> back(data.size() + 1);
  uLongf size = static_cast<uLongf>(back.size());
  // uncompress checks the header and the checksum.
  ASSERT_EQ(uncompress(back.data(), &size, stream.data(), static_cast<uLong>(stream.size())), Z_OK);
  back.resize(size);
  EXPECT_EQ(back, data);
}

TEST(ZlibStream, Crc32IsZlibsAndAnEmptyPieceChangesNoChecksum) {
  const std::vector<std::uint8_t> data = frame_like_bytes(100003, 5);
  const auto zlibs = static_cast<std::uint32_t>(crc32(0, data.data(), static_cast<uInt>(data.size())));
  EXPECT_EQ(crc32_of(data), zlibs);
  EXPECT_EQ(crc32_of(std::span(data).subspan(500), crc32_of(std::span(data).first(500))), zlibs);
  // An empty piece, even one without a buffer, leaves either checksum as it was.
  EXPECT_EQ(crc32_of(std::span<const std::uint8_t>(), zlibs), zlibs);
  EXPECT_EQ(adler32_of(std::span<const std::uint8_t>(), 12345u), 12345u);
}

}  // namespace
}  // namespace farm
