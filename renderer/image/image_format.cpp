#include "renderer/image/image_format.h"

#include <array>
#include <cstring>

namespace farm {

ImageFormat sniff_image_format(std::FILE* in) {
  std::array<unsigned char, 4> magic{};
  const std::size_t got = std::fread(magic.data(), 1, magic.size(), in);
  std::rewind(in);
  if (got >= 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01) return ImageFormat::exr;
  if (got >= 4 && magic[0] == 0x89 && magic[1] == 'P' && magic[2] == 'N' && magic[3] == 'G') return ImageFormat::png;
  if (got >= 3 && magic[0] == 0xff && magic[1] == 0xd8 && magic[2] == 0xff) return ImageFormat::jpeg;
  // Radiance files start "#?RADIANCE" or "#?RGBE" (rgbe_reader checks the rest).
  if (got >= 2 && magic[0] == '#' && magic[1] == '?') return ImageFormat::radiance;
  return ImageFormat::unknown;
}

}  // namespace farm
