#include "server/common/tile_codec.h"

#include <fmt/format.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>

#include "renderer/util/input_error.h"

namespace farm {

// The wire format is little-endian; every machine we build for is too, so planes are plain
// copies of the floats.
static_assert(std::endian::native == std::endian::little,
              "tile_codec copies floats as they lie in memory; add byte swapping for big-endian");

namespace {

// Copies the `components` floats of each pixel's value `get(x, y)` into one plane.
template <typename Get>
std::string pack(const Rect& r, int components, Get&& get) {
  const std::size_t pixel_bytes = sizeof(float) * static_cast<std::size_t>(components);
  std::string plane(static_cast<std::size_t>(r.width()) * static_cast<std::size_t>(r.height()) *
                        pixel_bytes,
                    '\0');
  char* at = plane.data();
  for (int y = r.y0; y < r.y1; ++y) {
    for (int x = r.x0; x < r.x1; ++x, at += pixel_bytes) {
      const auto value = get(x, y);
      static_assert(sizeof value % sizeof(float) == 0);
      std::memcpy(at, &value, pixel_bytes);
    }
  }
  return plane;
}

// `plane` holds exactly r's pixels of `components` floats: decode_tile checked every plane's size
// before it made the buffer.
template <typename Get>
void unpack(const Rect& r, int components, const std::string& plane, Get&& get) {
  const std::size_t pixel_bytes = sizeof(float) * static_cast<std::size_t>(components);
  const char* at = plane.data();
  for (int y = r.y0; y < r.y1; ++y) {
    for (int x = r.x0; x < r.x1; ++x, at += pixel_bytes) std::memcpy(get(x, y), at, pixel_bytes);
  }
}

}  // namespace

v1::TileRect to_proto(const Rect& r) {
  v1::TileRect t;
  t.set_x0(r.x0);
  t.set_y0(r.y0);
  t.set_x1(r.x1);
  t.set_y1(r.y1);
  return t;
}

Rect rect_of(const v1::TileRect& r) { return {r.x0(), r.y0(), r.x1(), r.y1()}; }

void encode_tile(const TileBuffer& t, v1::TileData& out) {
  const Rect& r = t.rect();
  out.Clear();
  *out.mutable_rect() = to_proto(r);
  out.set_width(r.width());
  out.set_height(r.height());
  out.set_rgba(pack(r, 4, [&](int x, int y) { return t.rgba(x, y); }));
  const AovSet& a = t.aovs();
  if (a.depth) out.set_depth(pack(r, 1, [&](int x, int y) { return t.depth(x, y); }));
  if (a.normal) out.set_normal(pack(r, 3, [&](int x, int y) { return t.normal(x, y); }));
  if (a.albedo) out.set_albedo(pack(r, 3, [&](int x, int y) { return t.albedo(x, y); }));
  if (a.bvh_cost) out.set_bvh_cost(pack(r, 1, [&](int x, int y) { return t.bvh_cost(x, y); }));
  if (a.variance) out.set_variance(pack(r, 3, [&](int x, int y) { return t.variance(x, y); }));
}

void encode_stats(const RenderStats& s, v1::TileStats& out) {
  out.set_samples(s.samples);
  out.set_invalid_samples(s.invalid_samples);
  out.set_fragments(s.fragments);
  out.set_rays(s.rays);
}

TileBuffer decode_tile(const v1::TileData& d) {
  const Rect r = rect_of(d.rect());
  // In 64 bits: the corners come off the wire, and x1 - x0 of two int32 can overflow an int.
  const std::int64_t width = std::int64_t{r.x1} - r.x0;
  const std::int64_t height = std::int64_t{r.y1} - r.y0;
  if (width <= 0 || height <= 0 || width != d.width() || height != d.height()) {
    throw InputError(fmt::format("tile rect [{}, {}) x [{}, {}) is empty or disagrees with its "
                                 "size {}x{}", r.x0, r.x1, r.y0, r.y1, d.width(), d.height()));
  }
  // Every plane's size is held against the rect before the buffer is made: a reply of a few
  // bytes claiming a 60000x60000 rect would otherwise allocate 57 GB first and be refused after.
  const auto pixels = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  const auto check_size = [&](const std::string& plane, std::uint64_t components, const char* name,
                              bool optional) {
    if (optional && plane.empty()) return;
    if (plane.size() / sizeof(float) / components != pixels ||
        plane.size() % (sizeof(float) * components) != 0) {
      throw InputError(fmt::format("tile {}: {} bytes for {}x{} pixels, expected {}", name,
                                   plane.size(), width, height, pixels * components * sizeof(float)));
    }
  };
  check_size(d.rgba(), 4, "rgba", false);
  check_size(d.depth(), 1, "depth", true);
  check_size(d.normal(), 3, "normal", true);
  check_size(d.albedo(), 3, "albedo", true);
  check_size(d.bvh_cost(), 1, "bvh_cost", true);
  check_size(d.variance(), 3, "variance", true);
  AovSet aovs;
  aovs.depth = !d.depth().empty();
  aovs.normal = !d.normal().empty();
  aovs.albedo = !d.albedo().empty();
  aovs.bvh_cost = !d.bvh_cost().empty();
  aovs.variance = !d.variance().empty();
  TileBuffer t;
  t.reset_for_overwrite(r, aovs);
  unpack(r, 4, d.rgba(), [&](int x, int y) { return &t.rgba(x, y); });
  if (aovs.depth) unpack(r, 1, d.depth(), [&](int x, int y) { return &t.depth(x, y); });
  if (aovs.normal) unpack(r, 3, d.normal(), [&](int x, int y) { return &t.normal(x, y); });
  if (aovs.albedo) unpack(r, 3, d.albedo(), [&](int x, int y) { return &t.albedo(x, y); });
  if (aovs.bvh_cost) {
    unpack(r, 1, d.bvh_cost(), [&](int x, int y) { return &t.bvh_cost(x, y); });
  }
  if (aovs.variance) {
    unpack(r, 3, d.variance(), [&](int x, int y) { return &t.variance(x, y); });
  }
  return t;
}

RenderStats decode_stats(const v1::TileStats& s) {
  RenderStats r;
  r.samples = s.samples();
  r.invalid_samples = s.invalid_samples();
  r.fragments = s.fragments();
  r.rays = s.rays();
  return r;
}

}  // namespace farm
