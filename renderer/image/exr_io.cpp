#include "renderer/image/exr_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfThreading.h>
#include <Iex.h>
#include <fmt/format.h>

#include <Imath/half.h>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "renderer/image/output_file.h"
#include "renderer/util/thread_pool.h"

namespace farm {
namespace {

// One EXR channel and how to read its value out of a TileBuffer pixel.
struct ChannelSpec {
  const char* name;
  bool always_float;
  std::function<float(const TileBuffer&, int, int)> get;
  std::function<void(TileBuffer&, int, int, float)> set;
};

std::vector<ChannelSpec> channels_for(const AovSet& aovs) {
  std::vector<ChannelSpec> specs;
  const char* rgba_names[] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c) {
    specs.push_back({rgba_names[c], false,
                     [c](const TileBuffer& t, int x, int y) { return t.rgba(x, y)[c]; },
                     [c](TileBuffer& t, int x, int y, float v) { t.rgba(x, y)[c] = v; }});
  }
  if (aovs.depth) {
    specs.push_back({"Z", true, [](const TileBuffer& t, int x, int y) { return t.depth(x, y); },
                     [](TileBuffer& t, int x, int y, float v) { t.depth(x, y) = v; }});
  }
  if (aovs.normal) {
    const char* names[] = {"N.X", "N.Y", "N.Z"};
    for (int c = 0; c < 3; ++c) {
      specs.push_back({names[c], false,
                       [c](const TileBuffer& t, int x, int y) { return t.normal(x, y)[c]; },
                       [c](TileBuffer& t, int x, int y, float v) { t.normal(x, y)[c] = v; }});
    }
  }
  if (aovs.albedo) {
    const char* names[] = {"albedo.R", "albedo.G", "albedo.B"};
    for (int c = 0; c < 3; ++c) {
      specs.push_back({names[c], false,
                       [c](const TileBuffer& t, int x, int y) { return t.albedo(x, y)[c]; },
                       [c](TileBuffer& t, int x, int y, float v) { t.albedo(x, y)[c] = v; }});
    }
  }
  if (aovs.bvh_cost) {
    specs.push_back({"bvh_cost", true,
                     [](const TileBuffer& t, int x, int y) { return t.bvh_cost(x, y); },
                     [](TileBuffer& t, int x, int y, float v) { t.bvh_cost(x, y) = v; }});
  }
  return specs;
}

}  // namespace

void write_exr(const TileBuffer& image, const std::filesystem::path& file, ExrPixelType type) {
  const Rect& r = image.rect();
  if (r.empty()) throw std::invalid_argument(fmt::format("{}: cannot write an empty image", file.string()));
  const int width = r.width(), height = r.height();
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);

  Imf::Header header(Imath::Box2i({r.x0, r.y0}, {r.x1 - 1, r.y1 - 1}),
                     Imath::Box2i({r.x0, r.y0}, {r.x1 - 1, r.y1 - 1}));
  header.compression() = Imf::ZIP_COMPRESSION;
  header.zipCompressionLevel() = 1;  // 2% larger than the default level, at about half the time
  Imf::FrameBuffer frame;

  // Planar copies of each channel in the pixel type it is stored as.
  const std::vector<ChannelSpec> specs = channels_for(image.aovs());
  std::vector<std::vector<float>> float_planes;
  std::vector<std::vector<Imath::half>> half_planes;
  float_planes.reserve(specs.size());
  half_planes.reserve(specs.size());
  // Slice base pointers are expressed relative to the data window origin, as OpenEXR expects.
  const std::ptrdiff_t origin = static_cast<std::ptrdiff_t>(r.y0) * width + r.x0;
  for (const ChannelSpec& spec : specs) {
    const bool as_float = spec.always_float || type == ExrPixelType::Float;
    header.channels().insert(spec.name, Imf::Channel(as_float ? Imf::FLOAT : Imf::HALF));
    if (as_float) {
      std::vector<float>& plane = float_planes.emplace_back(pixels);
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x)
          plane[static_cast<std::size_t>((y - r.y0) * width + (x - r.x0))] = spec.get(image, x, y);
      frame.insert(spec.name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(plane.data() - origin),
                                         sizeof(float), sizeof(float) * static_cast<std::size_t>(width)));
    } else {
      std::vector<Imath::half>& plane = half_planes.emplace_back(pixels);
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x)
          plane[static_cast<std::size_t>((y - r.y0) * width + (x - r.x0))] = Imath::half(spec.get(image, x, y));
      frame.insert(spec.name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(plane.data() - origin),
                                         sizeof(Imath::half),
                                         sizeof(Imath::half) * static_cast<std::size_t>(width)));
    }
  }

  // A frame's line blocks are compressed on OpenEXR's pool, one thread a core: compression is most
  // of a merge, which runs after the last tile while the farm waits for it.
  static std::once_flag pool;
  std::call_once(pool, [] { Imf::setGlobalThreadCount(resolve_thread_count(0)); });
  write_file_atomically(file, [&](const std::filesystem::path& temp) {
    try {
      Imf::OutputFile out(temp.c_str(), header, Imf::globalThreadCount());
      out.setFrameBuffer(frame);
      out.writePixels(height);
    } catch (const std::exception& e) {
      throw std::runtime_error(fmt::format("{}: cannot write EXR: {}", file.string(), e.what()));
    }
  });
}

TileBuffer read_exr(const std::filesystem::path& file) {
  try {
    Imf::InputFile in(file.c_str());
    const Imath::Box2i dw = in.header().dataWindow();
    const Rect r{dw.min.x, dw.min.y, dw.max.x + 1, dw.max.y + 1};
    const int width = r.width();
    const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(r.height());

    AovSet present;
    const Imf::ChannelList& channels = in.header().channels();
    if (channels.findChannel("Z")) present.depth = true;
    if (channels.findChannel("N.X")) present.normal = true;
    if (channels.findChannel("albedo.R")) present.albedo = true;
    if (channels.findChannel("bvh_cost")) present.bvh_cost = true;

    TileBuffer image(r, present);
    std::vector<ChannelSpec> specs = channels_for(present);
    std::vector<std::vector<float>> planes;
    planes.reserve(specs.size());
    Imf::FrameBuffer frame;
    const std::ptrdiff_t origin = static_cast<std::ptrdiff_t>(r.y0) * width + r.x0;
    for (const ChannelSpec& spec : specs) {
      std::vector<float>& plane = planes.emplace_back(pixels, spec.name[0] == 'A' ? 1.0f : 0.0f);
      frame.insert(spec.name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(plane.data() - origin),
                                         sizeof(float), sizeof(float) * static_cast<std::size_t>(width),
                                         1, 1, spec.name[0] == 'A' ? 1.0 : 0.0));
    }
    in.setFrameBuffer(frame);
    in.readPixels(dw.min.y, dw.max.y);
    for (std::size_t c = 0; c < specs.size(); ++c)
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x)
          specs[c].set(image, x, y, planes[c][static_cast<std::size_t>((y - r.y0) * width + (x - r.x0))]);
    return image;
  } catch (const Iex::BaseExc& e) {
    throw std::runtime_error(fmt::format("{}: cannot read EXR: {}", file.string(), e.what()));
  }
}

}  // namespace farm
