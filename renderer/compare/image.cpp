#include "renderer/compare/image.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <Iex.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <tuple>
#include <memory>
#include <stdexcept>

#include "renderer/image/image_limits.h"
#include "renderer/image/image_format.h"
#include "renderer/image/jpeg_reader.h"
#include "renderer/util/atomic_file.h"
#include "renderer/image/png_reader.h"
#include "renderer/image/png_writer.h"
#include "renderer/image/preview.h"
#include "renderer/image/rgb8_image.h"
#include "renderer/util/input_error.h"
#include "renderer/util/c_file.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

// Colour first, as image tools list them (R G B A), then every other channel by name.
int channel_rank(const std::string& name) {
  static constexpr std::array<const char*, 4> kFirst = {"R", "G", "B", "A"};
  for (std::size_t i = 0; i < kFirst.size(); ++i)
    if (name == kFirst[i]) return static_cast<int>(i);
  return static_cast<int>(kFirst.size());
}

Image read_exr_channels(const fs::path& file, int max_side) {
  try {
    Imf::InputFile in(file.c_str());
    const Imath::Box2i dw = in.header().dataWindow();
    const long long width = static_cast<long long>(dw.max.x) - dw.min.x + 1;
    const long long height = static_cast<long long>(dw.max.y) - dw.min.y + 1;
    if (width < 1 || height < 1 || width > max_side || height > max_side) {
      throw InputError(fmt::format("{}: a {}x{} data window is outside 1..{} pixels a side", file.string(), width,
                                   height, max_side));
    }
    std::vector<std::string> names;
    for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it) {
      if (it.channel().xSampling != 1 || it.channel().ySampling != 1) {
        throw InputError(fmt::format("{}: channel {} is subsampled, which comparisons do not support", file.string(),
                                     it.name()));
      }
      names.emplace_back(it.name());
    }
    if (names.empty()) throw InputError(fmt::format("{}: the EXR has no channels", file.string()));
    std::stable_sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
      const int ra = channel_rank(a), rb = channel_rank(b);
      return ra != rb ? ra < rb : (ra == 4 && a < b);
    });
    Image image = make_image(static_cast<int>(width), static_cast<int>(height), names);
    // OpenEXR writes each channel straight into the interleaved array (converting half to float),
    // addressed from the data window's corner.
    const std::size_t pixel = sizeof(float) * names.size();
    const std::size_t row = pixel * static_cast<std::size_t>(width);
    Imf::FrameBuffer frame;
    for (std::size_t c = 0; c < names.size(); ++c) {
      char* base = reinterpret_cast<char*>(image.values.data() + c) - static_cast<std::ptrdiff_t>(dw.min.x) * static_cast<std::ptrdiff_t>(pixel) -
                   static_cast<std::ptrdiff_t>(dw.min.y) * static_cast<std::ptrdiff_t>(row);
      frame.insert(names[c], Imf::Slice(Imf::FLOAT, base, pixel, row));
    }
    in.setFrameBuffer(frame);
    in.readPixels(dw.min.y, dw.max.y);
    return image;
  } catch (const Iex::BaseExc& e) {
    throw InputError(fmt::format("{}: cannot read EXR: {}", file.string(), e.what()));
  }
}

Image from_decoded(DecodedImage decoded) {
  static const std::vector<std::vector<std::string>> kNames = {
      {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
  Image image;
  image.width = decoded.width;
  image.height = decoded.height;
  image.channels = kNames[static_cast<std::size_t>(decoded.channels - 1)];
  image.values = std::move(decoded.values);
  image.display_referred = true;
  return image;
}

}  // namespace

int Image::channel(std::string_view name) const {
  for (std::size_t i = 0; i < channels.size(); ++i)
    if (channels[i] == name) return static_cast<int>(i);
  return -1;
}

Image make_image(int width, int height, std::vector<std::string> channels) {
  Image image;
  image.width = width;
  image.height = height;
  image.channels = std::move(channels);
  image.values.assign(image.pixel_count() * image.channels.size(), 0.0f);
  return image;
}

namespace {

CFile open_image(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) {
    throw InputError(fmt::format("{}: {}", file.string(), fs::exists(file, ec) ? "not a regular file" : "no such file"));
  }
  CFile in(std::fopen(file.c_str(), "rb"));
  if (!in) throw InputError(fmt::format("{}: cannot open for reading", file.string()));
  return in;
}

// The size and kind of the image open in `in` (its format sniffed already), from its header.
Image header_of(std::FILE* in, ImageFormat format, const fs::path& file) {
  Image header;
  try {
    switch (format) {
      case ImageFormat::exr: {
        Imf::InputFile exr(file.c_str());
        const Imath::Box2i dw = exr.header().dataWindow();
        header.width = dw.max.x - dw.min.x + 1;
        header.height = dw.max.y - dw.min.y + 1;
        return header;
      }
      case ImageFormat::png: std::tie(header.width, header.height) = read_png_size(in, file); break;
      case ImageFormat::jpeg: std::tie(header.width, header.height) = read_jpeg_size(in, file); break;
      case ImageFormat::radiance:
      case ImageFormat::unknown: throw InputError(fmt::format("{}: not an EXR, PNG or JPEG image", file.string()));
    }
  } catch (const InputError&) {
    throw;
  } catch (const Iex::BaseExc& e) {
    throw InputError(fmt::format("{}: cannot read EXR: {}", file.string(), e.what()));
  } catch (const std::exception& e) {  // the readers' errors already name the file
    throw InputError(e.what());
  }
  std::rewind(in);  // the decoder reads from the start
  header.display_referred = true;
  return header;
}

}  // namespace

Image read_image_header(const fs::path& file) {
  const CFile in = open_image(file);
  return header_of(in.get(), sniff_image_format(in.get()), file);
}

std::pair<Image, Image> read_images_to_compare(const fs::path& reference, const fs::path& test) {
  Image a = read_image_header(reference), b = read_image_header(test);
  if (a.width != b.width || a.height != b.height) return {std::move(a), std::move(b)};
  return {read_image(reference), read_image(test)};
}

Image read_image(const fs::path& file, int max_side) {
  if (max_side <= 0 || max_side > kMaxImageSide) max_side = kMaxImageSide;
  // One open, one sniff: the header is checked before the decoder is given the file.
  const CFile in = open_image(file);
  const ImageFormat format = sniff_image_format(in.get());
  const Image header = header_of(in.get(), format, file);
  const std::uint64_t pixels = static_cast<std::uint64_t>(std::max(0, header.width)) * static_cast<std::uint64_t>(std::max(0, header.height));
  if (pixels > kMaxComparedPixels) {
    throw InputError(fmt::format("{}: a {}x{} image ({} pixels) is more than the {} pixels (8192x8192) an image "
                                 "compared may have; it was not decoded",
                                 file.string(), header.width, header.height, pixels, kMaxComparedPixels));
  }
  try {
    switch (format) {
      case ImageFormat::exr: return read_exr_channels(file, max_side);
      case ImageFormat::png: return from_decoded(read_png(in.get(), file, max_side));
      case ImageFormat::jpeg: return from_decoded(read_jpeg(in.get(), file, max_side));
      case ImageFormat::radiance:
      case ImageFormat::unknown: break;  // header_of refused it
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {  // the readers' errors already name the file
    throw InputError(e.what());
  }
  throw InputError(fmt::format("{}: not an EXR, PNG or JPEG image", file.string()));
}

std::vector<int> colour_channels(const Image& image) {
  const int r = image.channel("R"), g = image.channel("G"), b = image.channel("B");
  if (r >= 0 && g >= 0 && b >= 0) return {r, g, b};
  if (const int y = image.channel("Y"); y >= 0) return {y};
  return {};
}

void write_png_image(const Image& image, const fs::path& file) {
  std::vector<int> source = colour_channels(image);
  if (source.empty() && !image.channels.empty()) source = {0};
  if (source.empty()) throw std::invalid_argument(fmt::format("{}: an image without channels", file.string()));
  if (source.size() == 1) source = {source[0], source[0], source[0]};
  Rgb8Image rgb;
  rgb.width = image.width;
  rgb.height = image.height;
  rgb.pixels.resize(image.pixel_count() * 3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (std::size_t c = 0; c < 3; ++c) {
        const float v = std::clamp(image.at(x, y, source[c]), 0.0f, 1.0f);  // NaN stays NaN here...
        const float safe = v == v ? v : 0.0f;                                    // ...and is shown black
        rgb.pixels[(static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) + static_cast<std::size_t>(x)) * 3 + c] =
            static_cast<std::uint8_t>(safe * 255.0f + 0.5f);
      }
  write_c_file_atomically(file, [&](std::FILE* out) { write_png(rgb, out, file); });
}

Image to_display(const Image& image) {
  std::vector<int> source = colour_channels(image);
  if (source.empty()) return {};
  if (source.size() == 1) source = {source[0], source[0], source[0]};
  Image out = make_image(image.width, image.height, {"R", "G", "B"});
  out.display_referred = true;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (std::size_t c = 0; c < 3; ++c) {
        const float v = image.at(x, y, source[c]);
        out.at(x, y, static_cast<int>(c)) = image.display_referred ? v : linear_to_srgb(v);
      }
  return out;
}

void write_exr_image(const Image& image, const fs::path& file) {
  if (image.pixel_count() == 0 || image.channels.empty()) {
    throw std::invalid_argument(fmt::format("{}: cannot write an empty image", file.string()));
  }
  Imf::Header header(image.width, image.height);
  header.compression() = Imf::ZIP_COMPRESSION;
  Imf::FrameBuffer frame;
  const std::size_t pixel = sizeof(float) * image.channels.size();
  const std::size_t row = pixel * static_cast<std::size_t>(image.width);
  for (std::size_t c = 0; c < image.channels.size(); ++c) {
    header.channels().insert(image.channels[c], Imf::Channel(Imf::FLOAT));
    // Slices are non-const in OpenEXR's API; a file being written only reads through them.
    frame.insert(image.channels[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(image.values.data() + c)),
                                               pixel, row));
  }
  write_file_atomically(file, [&](const fs::path& temp) {
    try {
      Imf::OutputFile out(temp.c_str(), header);
      out.setFrameBuffer(frame);
      out.writePixels(image.height);
    } catch (const std::exception& e) {
      throw std::runtime_error(fmt::format("{}: cannot write EXR: {}", file.string(), e.what()));
    }
  });
}

}  // namespace farm
