#include "renderer/image/exr_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfThreading.h>
#include <Iex.h>
#include <IexErrnoExc.h>
#include <fmt/format.h>

#include <Imath/half.h>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "renderer/image/float_to_half.h"
#include "renderer/util/atomic_file.h"
#include "renderer/util/thread_pool.h"

namespace farm {
namespace {

// One EXR channel as OpenEXR sees it in a TileBuffer: the channel's value in the first pixel and
// the distance to the next pixel. OpenEXR reads and writes the buffer's own arrays through these
// (converting to and from half itself, as Imath::half does), so no planar copy is made.
struct ChannelSlice {
  const char* name;
  bool always_float;   // depth, bvh_cost and variance keep full precision in a half EXR
  float* first;        // the value at the rect's top-left pixel
  std::size_t stride;  // bytes from one pixel to the next
};

std::vector<ChannelSlice> channel_slices(TileBuffer& t) {
  const Rect& r = t.rect();
  const int x = r.x0, y = r.y0;
  std::vector<ChannelSlice> slices;
  const char* rgba_names[] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c) slices.push_back({rgba_names[c], false, &t.rgba(x, y)[c], sizeof(glm::vec4)});
  const AovSet& aovs = t.aovs();
  if (aovs.depth) slices.push_back({"Z", true, &t.depth(x, y), sizeof(float)});
  if (aovs.normal) {
    const char* names[] = {"N.X", "N.Y", "N.Z"};
    for (int c = 0; c < 3; ++c) slices.push_back({names[c], false, &t.normal(x, y)[c], sizeof(glm::vec3)});
  }
  if (aovs.albedo) {
    const char* names[] = {"albedo.R", "albedo.G", "albedo.B"};
    for (int c = 0; c < 3; ++c) slices.push_back({names[c], false, &t.albedo(x, y)[c], sizeof(glm::vec3)});
  }
  if (aovs.bvh_cost) slices.push_back({"bvh_cost", true, &t.bvh_cost(x, y), sizeof(float)});
  if (aovs.variance) {
    const char* names[] = {"variance.R", "variance.G", "variance.B"};
    for (int c = 0; c < 3; ++c) slices.push_back({names[c], true, &t.variance(x, y)[c], sizeof(glm::vec3)});
  }
  return slices;
}

// A float slice over `slice` for OpenEXR, which addresses pixel (x, y) as base + x * xStride +
// y * yStride in data-window coordinates: the base is moved back from the rect's first pixel.
Imf::Slice float_slice(const ChannelSlice& slice, const Rect& r, double fill = 0.0) {
  const std::size_t row = slice.stride * static_cast<std::size_t>(r.width());
  char* base = reinterpret_cast<char*>(slice.first) - static_cast<std::ptrdiff_t>(r.x0) * static_cast<std::ptrdiff_t>(slice.stride) -
               static_cast<std::ptrdiff_t>(r.y0) * static_cast<std::ptrdiff_t>(row);
  return Imf::Slice(Imf::FLOAT, base, slice.stride, row, 1, 1, fill);
}

}  // namespace

void write_exr(const TileBuffer& image, const std::filesystem::path& file, ExrPixelType type) {
  const Rect& r = image.rect();
  if (r.empty()) throw std::invalid_argument(fmt::format("{}: cannot write an empty image", file.string()));
  const int height = r.height();

  Imf::Header header(Imath::Box2i({r.x0, r.y0}, {r.x1 - 1, r.y1 - 1}),
                     Imath::Box2i({r.x0, r.y0}, {r.x1 - 1, r.y1 - 1}));
  header.compression() = Imf::ZIP_COMPRESSION;
  header.zipCompressionLevel() = 1;  // 2% larger than the default level, at about half the time
  Imf::FrameBuffer frame;
  // Float channels are written straight from the buffer. OpenEXR's OutputFile does not convert
  // float to half, so half channels get a plane each, converted here (float_to_half.h).
  std::vector<std::vector<std::uint16_t>> half_planes;  // a half's bits each (float_to_half.h)
  const std::size_t width = static_cast<std::size_t>(r.width());
  // Slices are non-const in OpenEXR's API; a file being written only reads through them.
  for (const ChannelSlice& slice : channel_slices(const_cast<TileBuffer&>(image))) {
    const bool as_float = slice.always_float || type == ExrPixelType::Float;
    header.channels().insert(slice.name, Imf::Channel(as_float ? Imf::FLOAT : Imf::HALF));
    if (as_float) {
      frame.insert(slice.name, float_slice(slice, r));
      continue;
    }
    std::vector<std::uint16_t>& plane = half_planes.emplace_back(width * static_cast<std::size_t>(height));
    floats_to_halves(reinterpret_cast<const char*>(slice.first), slice.stride, plane.size(), plane.data());
    const std::ptrdiff_t origin = static_cast<std::ptrdiff_t>(r.y0) * r.width() + r.x0;
    frame.insert(slice.name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(plane.data() - origin),
                                        sizeof(std::uint16_t), sizeof(std::uint16_t) * width));
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
    } catch (const Iex::EnospcExc& e) {
      // The errno kept, so that a server tells a full disk from a broken image.
      throw std::system_error(ENOSPC, std::generic_category(), fmt::format("{}: cannot write EXR: {}", file.string(), e.what()));
    } catch (const Iex::EdquotExc& e) {
      throw std::system_error(EDQUOT, std::generic_category(), fmt::format("{}: cannot write EXR: {}", file.string(), e.what()));
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

    AovSet present;
    const Imf::ChannelList& channels = in.header().channels();
    if (channels.findChannel("Z")) present.depth = true;
    if (channels.findChannel("N.X")) present.normal = true;
    if (channels.findChannel("albedo.R")) present.albedo = true;
    if (channels.findChannel("bvh_cost")) present.bvh_cost = true;
    if (channels.findChannel("variance.R")) present.variance = true;

    // Channels the file lacks read as OpenEXR's fill value: alpha 1, the others 0.
    TileBuffer image(r, present);
    Imf::FrameBuffer frame;
    for (const ChannelSlice& slice : channel_slices(image)) {
      frame.insert(slice.name, float_slice(slice, r, slice.name[0] == 'A' ? 1.0 : 0.0));
    }
    in.setFrameBuffer(frame);
    in.readPixels(dw.min.y, dw.max.y);
    return image;
  } catch (const Iex::BaseExc& e) {
    throw std::runtime_error(fmt::format("{}: cannot read EXR: {}", file.string(), e.what()));
  }
}

}  // namespace farm
