#include "server/common/tile_result_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <optional>

#include "server/common/tile_codec.h"

namespace farm {

namespace {

// A unit normal's squared length is 1 within float rounding (normalize, then a transform in
// float); anything further off was not made by normalizing a vector.
constexpr float kUnitTolerance = 1e-3f;


std::string describe(const Rect& r) { return fmt::format("[{}, {}) x [{}, {})", r.x0, r.x1, r.y0, r.y1); }

std::string describe(float v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+inf" : "-inf";
  return fmt::format("{}", v);
}

// One plane of a tile: packed little-endian floats (tile_codec.h), `components` a pixel.
struct Plane {
  const char* name;
  const std::string* bytes;
  int components;
  bool wanted;

  float at(std::size_t pixel, int component) const {
    float v;
    std::memcpy(&v, bytes->data() + (pixel * static_cast<std::size_t>(components) + static_cast<std::size_t>(component)) * sizeof v,
                sizeof v);
    return v;
  }
};

// The tile's planes in TileData's order.
std::array<Plane, 6> planes_of(const v1::TileData& t, const AovSet& aovs) {
  return {{{"rgba", &t.rgba(), 4, true},
           {"depth", &t.depth(), 1, aovs.depth},
           {"normal", &t.normal(), 3, aovs.normal},
           {"albedo", &t.albedo(), 3, aovs.albedo},
           {"bvh_cost", &t.bvh_cost(), 1, aovs.bvh_cost},
           {"variance", &t.variance(), 3, aovs.variance}}};
}

// Checks every pixel's values; each check returns its complaint or nothing.
class PixelCheck {
 public:
  PixelCheck(const v1::TileData& tile, const RenderSettings& settings, const Rect& rect)
      : settings_(settings), rect_(rect), planes_(planes_of(tile, settings.aovs)) {}

  std::string run() const {
    const std::size_t pixels = static_cast<std::size_t>(rect_.width()) * static_cast<std::size_t>(rect_.height());
    for (std::size_t p = 0; p < pixels; ++p) {
      if (std::optional<std::string> problem = pixel(p)) {
        const int x = rect_.x0 + static_cast<int>(p % static_cast<std::size_t>(rect_.width()));
        const int y = rect_.y0 + static_cast<int>(p / static_cast<std::size_t>(rect_.width()));
        return fmt::format("pixel ({}, {}): {}", x, y, *problem);
      }
    }
    return {};
  }

 private:
  const Plane& rgba() const { return planes_[0]; }
  const Plane& depth() const { return planes_[1]; }
  const Plane& normal() const { return planes_[2]; }
  const Plane& albedo() const { return planes_[3]; }
  const Plane& bvh_cost() const { return planes_[4]; }
  const Plane& variance() const { return planes_[5]; }

  std::optional<std::string> pixel(std::size_t p) const {
    static constexpr const char* kRgba[] = {"R", "G", "B", "A"};
    for (int c = 0; c < 4; ++c) {
      const float v = rgba().at(p, c);
      if (!std::isfinite(v)) return fmt::format("rgba plane: {} is {} (engines drop non-finite samples)", kRgba[c], describe(v));
    }
    const float alpha = rgba().at(p, 3);
    if (alpha < 0.0f || alpha > 1.0f) return fmt::format("rgba plane: A (coverage) is {}, outside [0, 1]", describe(alpha));

    // Where nothing was hit the engines leave depth +inf and normal and albedo zero.
    std::optional<bool> hit;
    if (depth().wanted) {
      const float d = depth().at(p, 0);
      if (!(d > 0.0f)) return fmt::format("depth plane: {} (a depth is positive, or +inf where nothing was hit)", describe(d));
      hit = !std::isinf(d);
      // One sample: the pixel is covered exactly when that sample, the one its depth comes from, hit.
      if (settings_.spp <= 1 && alpha != (*hit ? 1.0f : 0.0f)) {
        return fmt::format("rgba plane: A is {} with one sample a pixel, but its depth says {}", describe(alpha),
                           *hit ? "hit" : "no hit");
      }
    }
    if (normal().wanted) {
      const float x = normal().at(p, 0), y = normal().at(p, 1), z = normal().at(p, 2);
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
        return fmt::format("normal plane: ({}, {}, {}) is not finite", describe(x), describe(y), describe(z));
      }
      const bool zero = x == 0.0f && y == 0.0f && z == 0.0f;
      const float length2 = x * x + y * y + z * z;
      if (!zero && std::fabs(length2 - 1.0f) > kUnitTolerance) {
        return fmt::format("normal plane: ({}, {}, {}) has length {}; a normal is unit, or zero where nothing was hit",
                           x, y, z, std::sqrt(length2));
      }
      if (hit && zero == *hit) {
        return fmt::format("normal plane: ({}, {}, {}) where depth says {}", x, y, z, *hit ? "hit" : "no hit");
      }
    }
    if (albedo().wanted) {
      const float r = albedo().at(p, 0), g = albedo().at(p, 1), b = albedo().at(p, 2);
      if (!std::isfinite(r) || !std::isfinite(g) || !std::isfinite(b)) {
        return fmt::format("albedo plane: ({}, {}, {}) is not finite", describe(r), describe(g), describe(b));
      }
      if (hit && !*hit && (r != 0.0f || g != 0.0f || b != 0.0f)) {
        return fmt::format("albedo plane: ({}, {}, {}) where nothing was hit (0 there)", r, g, b);
      }
    }
    if (bvh_cost().wanted) {
      const float c = bvh_cost().at(p, 0);
      if (settings_.engine == EngineKind::Whitted) {
        if (!std::isfinite(c) || c < 0.0f || c != std::floor(c)) {
          return fmt::format("bvh_cost plane: {} is no count of nodes and triangles", describe(c));
        }
      } else if (c != 0.0f) {
        return fmt::format("bvh_cost plane: {} from the {} engine, which writes 0", describe(c), to_string(settings_.engine));
      }
    }
    if (variance().wanted) {
      for (int c = 0; c < 3; ++c) {
        const float v = variance().at(p, c);
        if (settings_.engine == EngineKind::Path) {
          if (!std::isfinite(v) || v < 0.0f) return fmt::format("variance plane: {} (a variance is finite and >= 0)", describe(v));
        } else if (v != 0.0f) {
          return fmt::format("variance plane: {} from the {} engine, which writes 0", describe(v), to_string(settings_.engine));
        }
      }
    }
    return std::nullopt;
  }

  const RenderSettings& settings_;
  Rect rect_;
  std::array<Plane, 6> planes_;
};

std::string check_stats(const v1::TileStats& s, const RenderSettings& settings, std::uint64_t pixels) {
  for (const auto& [name, value] : {std::pair{"render_ms", s.render_ms()}, std::pair{"prepare_ms", s.prepare_ms()},
                                    std::pair{"cpu_ms", s.cpu_ms()}}) {
    if (!std::isfinite(value) || value < 0.0) return fmt::format("stats: {} is {}", name, value);
  }
  if (s.threads() < 0) return fmt::format("stats: threads is {}", s.threads());
  // Those of the call's sample pass (all spp without passes).
  const std::uint64_t samples =
      settings.engine == EngineKind::Path ? pixels * static_cast<std::uint64_t>(samples_to_render(settings).count()) : 0;
  if (s.samples() != samples) {
    return fmt::format("stats: {} samples, the {} engine takes {} for {} pixels", s.samples(),
                       to_string(settings.engine), samples, pixels);
  }
  if (s.invalid_samples() > s.samples()) {
    return fmt::format("stats: {} invalid samples of {}", s.invalid_samples(), s.samples());
  }
  return {};
}

}  // namespace

Rect answered_rect(const RenderSettings& settings, const Rect& asked) {
  return asked.intersect(Rect{0, 0, settings.width, settings.height});
}

std::string check_tile_reply(const v1::RenderTileResponse& reply, const RenderSettings& settings,
                             const Rect& asked) {
  const v1::TileData& tile = reply.tile();
  const Rect expected = answered_rect(settings, asked);
  const Rect rect = rect_of(tile.rect());
  if (rect != expected) {
    return fmt::format("its rect {} is not the {} asked for", describe(rect), describe(expected));
  }
  if (tile.width() != rect.width() || tile.height() != rect.height()) {
    return fmt::format("its size {}x{} is not its rect's {}x{}", tile.width(), tile.height(), rect.width(), rect.height());
  }
  const std::size_t pixels = static_cast<std::size_t>(rect.width()) * static_cast<std::size_t>(rect.height());
  for (const Plane& plane : planes_of(tile, settings.aovs)) {
    const std::size_t expected_bytes = plane.wanted ? pixels * static_cast<std::size_t>(plane.components) * sizeof(float) : 0;
    if (plane.bytes->size() == expected_bytes) continue;
    if (!plane.wanted) return fmt::format("its {} plane holds {} bytes; the job did not ask for it", plane.name, plane.bytes->size());
    if (plane.bytes->empty()) return fmt::format("its {} plane is missing", plane.name);
    return fmt::format("its {} plane holds {} bytes, not the {} of {}x{} pixels", plane.name, plane.bytes->size(),
                       expected_bytes, rect.width(), rect.height());
  }
  if (std::string problem = PixelCheck(tile, settings, rect).run(); !problem.empty()) return problem;
  return check_stats(reply.stats(), settings, pixels);
}

bool same_tile_bits(const v1::TileData& a, const v1::TileData& b) {
  return rect_of(a.rect()) == rect_of(b.rect()) && a.width() == b.width() && a.height() == b.height() &&
         a.rgba() == b.rgba() && a.depth() == b.depth() && a.normal() == b.normal() && a.albedo() == b.albedo() &&
         a.bvh_cost() == b.bvh_cost() && a.variance() == b.variance();
}

v1::TileData crop_tile(const v1::TileData& tile, const Rect& rect) {
  const Rect from = rect_of(tile.rect());
  v1::TileData out;
  *out.mutable_rect() = to_proto(rect);
  out.set_width(rect.width());
  out.set_height(rect.height());
  const auto crop = [&](const std::string& plane, std::string* to) {
    if (plane.empty()) return;
    const std::size_t pixel_bytes = plane.size() / (static_cast<std::size_t>(from.width()) * static_cast<std::size_t>(from.height()));
    const std::size_t row_bytes = static_cast<std::size_t>(rect.width()) * pixel_bytes;
    to->reserve(row_bytes * static_cast<std::size_t>(rect.height()));
    for (int y = rect.y0; y < rect.y1; ++y) {
      const std::size_t at = (static_cast<std::size_t>(y - from.y0) * static_cast<std::size_t>(from.width()) +
                              static_cast<std::size_t>(rect.x0 - from.x0)) * pixel_bytes;
      to->append(plane, at, row_bytes);
    }
  };
  crop(tile.rgba(), out.mutable_rgba());
  crop(tile.depth(), out.mutable_depth());
  crop(tile.normal(), out.mutable_normal());
  crop(tile.albedo(), out.mutable_albedo());
  crop(tile.bvh_cost(), out.mutable_bvh_cost());
  crop(tile.variance(), out.mutable_variance());
  return out;
}

}  // namespace farm
