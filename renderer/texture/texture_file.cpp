#include "renderer/texture/texture_file.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfStdIO.h>
#include <ImfVersion.h>
#include <ImfXdr.h>
#include <Iex.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "renderer/image/image_format.h"
#include "renderer/image/jpeg_reader.h"
#include "renderer/image/png_reader.h"
#include "renderer/texture/rgbe_reader.h"
#include "renderer/util/input_error.h"
#include "renderer/util/c_file.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

float srgb_to_linear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }

void check_size(const fs::path& file, std::int64_t width, std::int64_t height) {
  const std::uint64_t texels = static_cast<std::uint64_t>(std::max<std::int64_t>(0, width)) *
                               static_cast<std::uint64_t>(std::max<std::int64_t>(0, height));
  if (width <= 0 || height <= 0 || width > kMaxTextureSide || height > kMaxTextureSide || texels > kMaxTextureTexels) {
    throw InputError(fmt::format("{}: a {}x{} texture is larger than a texture may be ({} on a side, {} texels); it "
                                 "was not decoded",
                                 file.string(), width, height, kMaxTextureSide, kMaxTextureTexels));
  }
}

// A PNG's or JPEG's stored values to RGBA: grey copied to R G B, alpha 1 where there is none,
// colour sRGB-decoded when the texture is colour.
std::shared_ptr<const Texture> from_decoded(const DecodedImage& image, TextureColourSpace space) {
  const bool decode = space == TextureColourSpace::Srgb;
  const auto colour = [&](float v) { return decode ? srgb_to_linear(v) : v; };
  const auto n = static_cast<std::size_t>(image.channels);
  std::vector<glm::vec4> texels(static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height));
  for (std::size_t i = 0; i < texels.size(); ++i) {
    const float* v = &image.values[i * n];
    const bool grey = n <= 2;
    const float alpha = n == 2 ? v[1] : n == 4 ? v[3] : 1.0f;
    texels[i] = grey ? glm::vec4(glm::vec3(colour(v[0])), alpha) : glm::vec4(colour(v[0]), colour(v[1]), colour(v[2]), alpha);
  }
  return std::make_shared<const Texture>(image.width, image.height, std::move(texels));
}

// An EXR's data window from its header alone. Imf::InputFile would first read the table of line
// offsets, which the data window sizes: a hostile header would make it allocate for it.
Imath::Box2i exr_data_window(const fs::path& file) {
  Imf::StdIFStream stream(file.c_str());
  int magic = 0, version = 0;
  Imf::Xdr::read<Imf::StreamIO>(stream, magic);
  Imf::Xdr::read<Imf::StreamIO>(stream, version);
  if (magic != Imf::MAGIC) throw InputError(fmt::format("{}: not an OpenEXR file", file.string()));
  Imf::Header header;
  header.readFrom(stream, version);
  return header.dataWindow();
}

// An EXR's R G B (A), or Y (A) for a grey one, as stored; alpha 1 where it has none. Only those
// channels are read (a render's AOVs in the same file are not), straight into the texels.
std::shared_ptr<const Texture> read_exr_texture(const fs::path& file) {
  try {
    const Imath::Box2i claimed = exr_data_window(file);
    check_size(file, std::int64_t{claimed.max.x} - claimed.min.x + 1, std::int64_t{claimed.max.y} - claimed.min.y + 1);
    Imf::InputFile in(file.c_str());
    const Imath::Box2i window = in.header().dataWindow();
    const std::int64_t width = std::int64_t{window.max.x} - window.min.x + 1;
    const std::int64_t height = std::int64_t{window.max.y} - window.min.y + 1;
    check_size(file, width, height);
    const Imf::ChannelList& channels = in.header().channels();
    const bool rgb = channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
    if (!rgb && !channels.findChannel("Y")) {
      throw InputError(fmt::format("{}: the EXR has neither R, G and B nor Y channels", file.string()));
    }
    std::vector<glm::vec4> texels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
    // OpenEXR addresses pixel (x, y) of the data window as base + x * xStride + y * yStride.
    const std::size_t pixel = sizeof(glm::vec4), row = pixel * static_cast<std::size_t>(width);
    char* const base = reinterpret_cast<char*>(texels.data()) -
                       static_cast<std::ptrdiff_t>(window.min.x) * static_cast<std::ptrdiff_t>(pixel) -
                       static_cast<std::ptrdiff_t>(window.min.y) * static_cast<std::ptrdiff_t>(row);
    Imf::FrameBuffer frame;
    const auto slice = [&](const char* name, std::size_t component, double fill) {
      frame.insert(name, Imf::Slice(Imf::FLOAT, base + component * sizeof(float), pixel, row, 1, 1, fill));
    };
    if (rgb) {
      slice("R", 0, 0.0);
      slice("G", 1, 0.0);
      slice("B", 2, 0.0);
    } else {
      slice("Y", 0, 0.0);
    }
    slice("A", 3, 1.0);  // a file without alpha: OpenEXR fills the slice with 1
    in.setFrameBuffer(frame);
    in.readPixels(window.min.y, window.max.y);
    if (!rgb) {
      for (glm::vec4& t : texels) t.y = t.z = t.x;
    }
    return std::make_shared<const Texture>(static_cast<int>(width), static_cast<int>(height), std::move(texels));
  } catch (const Iex::BaseExc& e) {
    throw InputError(fmt::format("{}: cannot read EXR: {}", file.string(), e.what()));
  }
}

// A PNG or JPEG open in `in`: its size checked from the header, then decoded.
std::shared_ptr<const Texture> read_png_or_jpeg(std::FILE* in, ImageFormat format, const fs::path& name,
                                                TextureColourSpace space) {
  if (format == ImageFormat::png) {
    const auto [width, height] = read_png_size(in, name);
    check_size(name, width, height);
    return from_decoded(read_png(in, name, kMaxTextureSide), space);
  }
  const auto [width, height] = read_jpeg_size(in, name);
  std::rewind(in);
  check_size(name, width, height);
  return from_decoded(read_jpeg(in, name, kMaxTextureSide), space);
}

}  // namespace

std::shared_ptr<const Texture> load_texture_bytes(std::span<const unsigned char> encoded, const std::string& name,
                                                  TextureColourSpace space) {
  if (encoded.empty()) throw InputError(fmt::format("{}: an empty image", name));
  // libpng and libjpeg read a FILE: the bytes are handed to them as one, read-only.
  CFile in(fmemopen(const_cast<unsigned char*>(encoded.data()), encoded.size(), "rb"));
  if (!in) throw InputError(fmt::format("{}: cannot read the image from memory", name));
  try {
    const ImageFormat format = sniff_image_format(in.get());
    if (format == ImageFormat::png || format == ImageFormat::jpeg) return read_png_or_jpeg(in.get(), format, name, space);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {  // the readers' errors name the image already
    throw InputError(e.what());
  }
  throw InputError(fmt::format("{}: an image embedded in a model must be a PNG or a JPEG", name));
}

std::shared_ptr<const Texture> load_texture_file(const fs::path& file, TextureColourSpace space) {
  CFile in(std::fopen(file.c_str(), "rb"));
  if (!in) throw InputError(fmt::format("{}: cannot open the texture for reading", file.string()));
  try {
    switch (const ImageFormat format = sniff_image_format(in.get())) {
      case ImageFormat::png:
      case ImageFormat::jpeg: return read_png_or_jpeg(in.get(), format, file, space);
      case ImageFormat::exr:
        in.reset();
        return read_exr_texture(file);
      case ImageFormat::radiance: {
        in.reset();
        RgbeImage hdr = read_rgbe(file, kMaxTextureSide, kMaxTextureTexels);
        return std::make_shared<const Texture>(hdr.width, hdr.height, std::move(hdr.texels));
      }
      case ImageFormat::unknown: break;
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {  // the readers' errors name the file already
    throw InputError(e.what());
  }
  throw InputError(fmt::format("{}: not a PNG, JPEG, OpenEXR or Radiance HDR image", file.string()));
}

}  // namespace farm
