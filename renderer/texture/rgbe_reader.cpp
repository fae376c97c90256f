#include "renderer/texture/rgbe_reader.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "renderer/util/input_error.h"
#include "renderer/util/c_file.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

// One header line, without its newline; false at the end of the file. Lines longer than a
// header could need are refused.
bool read_line(std::FILE* in, std::string& line, const fs::path& file) {
  line.clear();
  for (int c = std::fgetc(in); c != EOF; c = std::fgetc(in)) {
    if (c == '\n') return true;
    line.push_back(static_cast<char>(c));
    if (line.size() > 4096) throw InputError(fmt::format("{}: Radiance header line too long", file.string()));
  }
  return !line.empty();
}

// RGBE to linear: the mantissas scaled by 2^(e - 128 - 8), as the format's writers store them.
glm::vec4 to_linear(const unsigned char* rgbe) {
  if (rgbe[3] == 0) return {0.0f, 0.0f, 0.0f, 1.0f};
  const float scale = std::ldexp(1.0f, static_cast<int>(rgbe[3]) - (128 + 8));
  return {rgbe[0] * scale, rgbe[1] * scale, rgbe[2] * scale, 1.0f};
}

}  // namespace

RgbeImage read_rgbe(const fs::path& file, int max_side, std::uint64_t max_texels) {
  const auto fail = [&](const std::string& what) -> InputError {
    return InputError(fmt::format("{}: cannot read Radiance HDR: {}", file.string(), what));
  };
  CFile in(std::fopen(file.c_str(), "rb"));
  if (!in) throw fail("cannot open it");
  std::string line;
  if (!read_line(in.get(), line, file) || (line != "#?RADIANCE" && line != "#?RGBE")) {
    throw fail("it does not start with #?RADIANCE or #?RGBE");
  }
  for (;;) {
    if (!read_line(in.get(), line, file)) throw fail("the header has no end");
    if (line.empty()) break;
    if (line.rfind("FORMAT=", 0) == 0 && line != "FORMAT=32-bit_rle_rgbe") throw fail("only 32-bit_rle_rgbe is read");
  }
  if (!read_line(in.get(), line, file)) throw fail("no resolution line");
  char y_axis[3] = {}, x_axis[3] = {};
  long height = 0, width = 0;
  if (std::sscanf(line.c_str(), "%2s %ld %2s %ld", y_axis, &height, x_axis, &width) != 4 ||
      std::strcmp(y_axis, "-Y") != 0 || std::strcmp(x_axis, "+X") != 0) {
    throw fail("only the standard orientation \"-Y height +X width\" is read, not \"" + line + "\"");
  }
  if (width <= 0 || height <= 0 || width > max_side || height > max_side ||
      static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) > max_texels) {
    throw InputError(fmt::format("{}: a {}x{} texture is larger than a texture may be ({} on a side, {} texels); it "
                                 "was not decoded",
                                 file.string(), width, height, max_side, max_texels));
  }
  RgbeImage out;
  out.width = static_cast<int>(width);
  out.height = static_cast<int>(height);
  out.texels.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  const std::size_t w = static_cast<std::size_t>(width);
  std::vector<unsigned char> row(w * 4);
  const auto byte = [&]() {
    const int c = std::fgetc(in.get());
    if (c == EOF) throw fail("the file ends inside its pixels");
    return static_cast<unsigned char>(c);
  };
  for (int y = 0; y < out.height; ++y) {
    unsigned char head[4];
    for (unsigned char& h : head) h = byte();
    const bool run_length = width >= 8 && width < 0x8000 && head[0] == 2 && head[1] == 2 && (head[2] & 0x80) == 0;
    if (!run_length) {
      // Flat: four bytes a pixel, the first pixel already read.
      std::memcpy(row.data(), head, 4);
      if (w > 1 && std::fread(row.data() + 4, 4, w - 1, in.get()) != w - 1) throw fail("the file ends inside its pixels");
    } else {
      if ((static_cast<std::size_t>(head[2]) << 8 | head[3]) != w) throw fail("a scanline's length is not the width");
      // Each channel of the row in turn, as runs (count > 128: one value count - 128 times) and
      // literals (count values); a count that runs past the row is refused.
      for (std::size_t channel = 0; channel < 4; ++channel) {
        for (std::size_t x = 0; x < w;) {
          unsigned count = byte();
          if (count > 128) {
            count -= 128;
            if (count > w - x) throw fail("a run goes past the end of its scanline");
            const unsigned char value = byte();
            for (unsigned k = 0; k < count; ++k) row[(x++) * 4 + channel] = value;
          } else {
            if (count == 0 || count > w - x) throw fail("a literal goes past the end of its scanline");
            for (unsigned k = 0; k < count; ++k) row[(x++) * 4 + channel] = byte();
          }
        }
      }
    }
    for (std::size_t x = 0; x < w; ++x) out.texels[static_cast<std::size_t>(y) * w + x] = to_linear(&row[x * 4]);
  }
  return out;
}

}  // namespace farm
