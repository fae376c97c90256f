#include "renderer/image/png_writer.h"

#include "renderer/image/png_strips.h"

namespace farm {

void write_png(const Rgb8Image& image, std::FILE* out, const std::filesystem::path& name) {
  write_png(rows_of(image), out, name);
}

void write_png(const Rgb8Rows& rows, std::FILE* out, const std::filesystem::path& name) {
  PngStrips png(rows.width, rows.height, name);
  for (int strip = 0; strip < png.strips(); ++strip) png.compress(strip, rows.row);
  png.write(out);
}

}  // namespace farm
