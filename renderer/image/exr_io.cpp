#include "renderer/image/exr_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <fcntl.h>
#include <openexr.h>
#include <unistd.h>
#include <Iex.h>
#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "renderer/image/exr_zip_block.h"
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

// The file being written, for OpenEXRCore's write callback: the temporary file's descriptor, and
// the errno of a write that failed (so that a full disk is told apart from a broken image).
struct ExrSink {
  int fd = -1;
  int write_errno = 0;
  std::string message;  // OpenEXRCore's last error message
};

std::int64_t write_at(exr_const_context_t, void* user, const void* buffer, std::uint64_t size, std::uint64_t offset,
                      exr_stream_error_func_ptr_t) {
  auto* sink = static_cast<ExrSink*>(user);
  const char* p = static_cast<const char*>(buffer);
  std::uint64_t done = 0;
  while (done < size) {
    const ssize_t n = ::pwrite(sink->fd, p + done, size - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      sink->write_errno = n < 0 ? errno : EIO;
      return -1;
    }
    done += static_cast<std::uint64_t>(n);
  }
  return static_cast<std::int64_t>(size);
}

void remember_error(exr_const_context_t ctxt, exr_result_t, const char* message) {
  void* user = nullptr;
  if (exr_get_user_data(ctxt, &user) == EXR_ERR_SUCCESS && user != nullptr) {
    static_cast<ExrSink*>(user)->message = message;
  }
}

// OpenEXRCore's calls, each checked: a failure throws, naming the file and what OpenEXR said.
void check(exr_result_t result, const ExrSink& sink, const std::filesystem::path& file) {
  if (result == EXR_ERR_SUCCESS) return;
  const std::string what = fmt::format("{}: cannot write EXR: {}", file.string(),
                                       sink.message.empty() ? exr_get_default_error_message(result) : sink.message);
  if (sink.write_errno != 0) throw std::system_error(sink.write_errno, std::generic_category(), what);
  throw std::runtime_error(what);
}

// Compresses a frame's chunks on `threads` threads (0: one a core, since compression is most of a
// merge, which runs after the last tile while the farm waits for it). One pool a size, made at its
// first use and kept for the process.
ThreadPool& chunk_pool(int threads) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<ThreadPool>> pools;
  const int size = resolve_thread_count(threads);
  const std::lock_guard lock(mutex);
  std::unique_ptr<ThreadPool>& pool = pools[size];
  if (!pool) pool = std::make_unique<ThreadPool>(size);
  return *pool;
}

}  // namespace

void write_exr(const TileBuffer& image, const std::filesystem::path& file, ExrPixelType type,
               const std::function<void(int y0, int y1)>& lines_packed, int threads) {
  const Rect& r = image.rect();
  if (r.empty()) throw std::invalid_argument(fmt::format("{}: cannot write an empty image", file.string()));
  const int width = r.width(), height = r.height();
  // Slices are non-const to share them with read_exr; a file being written only reads them.
  std::vector<ExrChannel> channels;
  for (const ChannelSlice& slice : channel_slices(const_cast<TileBuffer&>(image))) {
    const bool half = !slice.always_float && type == ExrPixelType::Half;
    channels.push_back({slice.name, half, reinterpret_cast<const char*>(slice.first), slice.stride,
                        slice.stride * static_cast<std::size_t>(width)});
  }
  // The file's channel order: sorted by name, byte by byte.
  std::sort(channels.begin(), channels.end(), [](const ExrChannel& a, const ExrChannel& b) { return a.name < b.name; });

  const std::size_t chunk_count = static_cast<std::size_t>((height + kExrZipLines - 1) / kExrZipLines);
  std::vector<std::vector<std::uint8_t>> chunks(chunk_count);
  chunk_pool(threads).parallel_for(chunk_count, 1, [&](std::size_t begin, std::size_t end, int) {
    for (std::size_t c = begin; c < end; ++c) {
      const int y0 = static_cast<int>(c) * kExrZipLines, y1 = std::min(height, y0 + kExrZipLines);
      chunks[c] = pack_zip_chunk(channels, width, y0, y1);
      if (lines_packed) lines_packed(y0, y1);
    }
  });

  write_file_atomically(file, [&](const std::filesystem::path& temp) {
    ExrSink sink;
    sink.fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (sink.fd < 0) {
      throw std::system_error(errno, std::generic_category(), fmt::format("{}: cannot write EXR", file.string()));
    }
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &sink;
    init.write_fn = write_at;
    init.error_handler_fn = remember_error;
    exr_context_t ctxt = nullptr;
    // Closed whichever way this ends; exr_finish writes the chunk table, so its result counts.
    const auto finish = [&] {
      exr_result_t result = EXR_ERR_SUCCESS;
      if (ctxt != nullptr) result = exr_finish(&ctxt);
      const int closed = sink.fd >= 0 ? ::close(sink.fd) : 0;
      const int close_errno = errno;
      sink.fd = -1;
      check(result, sink, file);
      if (closed != 0) {
        throw std::system_error(close_errno, std::generic_category(), fmt::format("{}: cannot write EXR", file.string()));
      }
    };
    try {
      check(exr_start_write(&ctxt, temp.c_str(), EXR_WRITE_FILE_DIRECTLY, &init), sink, file);
      int part = 0;
      check(exr_add_part(ctxt, nullptr, EXR_STORAGE_SCANLINE, &part), sink, file);
      const exr_attr_box2i_t window{{r.x0, r.y0}, {r.x1 - 1, r.y1 - 1}};
      const exr_attr_v2f_t centre{0.0f, 0.0f};
      check(exr_initialize_required_attr(ctxt, part, &window, &window, 1.0f, &centre, 1.0f,
                                         EXR_LINEORDER_INCREASING_Y, EXR_COMPRESSION_ZIP),
            sink, file);
      for (const ExrChannel& c : channels) {
        const int added = exr_add_channel(ctxt, part, c.name.c_str(), c.half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                                          EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
        check(added, sink, file);
      }
      check(exr_write_header(ctxt), sink, file);
      for (std::size_t c = 0; c < chunk_count; ++c) {
        check(exr_write_scanline_chunk(ctxt, part, r.y0 + static_cast<int>(c) * kExrZipLines, chunks[c].data(),
                                       chunks[c].size()),
              sink, file);
      }
    } catch (...) {
      try {
        finish();
      } catch (...) {
        // The first failure is the one reported.
      }
      throw;
    }
    finish();
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
