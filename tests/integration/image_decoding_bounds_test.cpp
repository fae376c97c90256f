// Bounded decoding (issue #32): an image's header is checked before its pixels are decoded. A PNG
// of about 1 MB that declares 16384 x 16384 (5 GB as floats once decoded; 6 GB at 16 bits) given
// to `farm compare` is refused from its header, naming the limit, or fails for its size without
// a pixel decoded; the command's peak memory stays under 200 MB either way.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <zlib.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

void put_be32(std::string& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xff));
}

void put_chunk(std::ofstream& file, const char* type, const std::string& data) {
  std::string chunk;
  put_be32(chunk, static_cast<std::uint32_t>(data.size()));
  chunk += type;
  chunk += data;
  const uLong crc = crc32(0, reinterpret_cast<const Bytef*>(chunk.data() + 4), static_cast<uInt>(chunk.size() - 4));
  put_be32(chunk, static_cast<std::uint32_t>(crc));
  file.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
}

// A grey PNG of `side` x `side` black pixels of `bits` bits, written as a stream: its rows of
// zeros deflate to a file a thousand times smaller than the image.
fs::path write_black_png(const fs::path& file, std::uint32_t side, int bits) {
  std::ofstream out(file, std::ios::binary);
  out.write("\x89PNG\r\n\x1a\n", 8);
  std::string ihdr;
  put_be32(ihdr, side);
  put_be32(ihdr, side);
  ihdr += static_cast<char>(bits);
  ihdr += std::string("\0\0\0\0", 4);  // grey; deflate; adaptive filtering; no interlace
  put_chunk(out, "IHDR", ihdr);
  z_stream z{};
  deflateInit(&z, 9);
  const std::vector<unsigned char> row(1 + side * static_cast<std::uint32_t>(bits / 8), 0);  // filter 0, zeros
  std::vector<unsigned char> buffer(1 << 20);
  std::string idat;
  for (std::uint32_t y = 0; y <= side; ++y) {
    const bool last = y == side;
    z.next_in = const_cast<unsigned char*>(row.data());
    z.avail_in = last ? 0 : static_cast<uInt>(row.size());
    do {
      z.next_out = buffer.data();
      z.avail_out = static_cast<uInt>(buffer.size());
      deflate(&z, last ? Z_FINISH : Z_NO_FLUSH);
      idat.append(reinterpret_cast<char*>(buffer.data()), buffer.size() - z.avail_out);
    } while (z.avail_out == 0);
  }
  deflateEnd(&z);
  put_chunk(out, "IDAT", idat);
  put_chunk(out, "IEND", "");
  return file;
}

// The largest resident size of the children this test waited for (each ctest test is a process
// of its own), in MiB.
long children_peak_mib() {
  rusage usage{};
  getrusage(RUSAGE_CHILDREN, &usage);
  return usage.ru_maxrss / 1024;
}

TEST(ImageDecodingBounds, FarmCompareRefusesAHugePngFromItsHeaderWithinTwoHundredMegabytes) {
  test::TempDir dir;
  const fs::path big8 = write_black_png(dir / "big8.png", 16384, 8);
  const fs::path big16 = write_black_png(dir / "big16.png", 16384, 16);
  const fs::path small = write_black_png(dir / "small.png", 64, 8);
  EXPECT_LT(fs::file_size(big8), 2u << 20);
  EXPECT_LT(fs::file_size(big16), 2u << 20);

  for (const fs::path& big : {big8, big16}) {
    SCOPED_TRACE(big.filename().string());
    // The same size: the header is over the limit, and nothing is decoded.
    test::CommandResult r = test::run_command(test::farm_command("compare " + big.string() + " " + big.string()));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("16384x16384"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("more than the 67108864 pixels"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(big.string()), std::string::npos) << r.output;
    // Sizes that differ: a FAIL that says so, from the headers alone.
    r = test::run_command(test::farm_command("compare " + small.string() + " " + big.string()));
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("sizes differ: reference 64x64, new 16384x16384"), std::string::npos) << r.output;
  }
  EXPECT_LT(children_peak_mib(), 200) << "farm compare's peak resident memory";
}

}  // namespace
}  // namespace farm
