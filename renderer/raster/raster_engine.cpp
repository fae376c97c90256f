#include "renderer/raster/raster_engine.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <vector>

#include "renderer/raster/sample_pattern.h"
#include "renderer/scene/blinn_phong.h"
#include "renderer/scene/radiance_limit.h"
#include "renderer/scene/shading_normal.h"
#include "renderer/texture/environment_light.h"
#include "renderer/texture/material_textures.h"
#include "renderer/util/mix64.h"

namespace farm::raster {
namespace {

// Triangles drawn into a bin between looks at the cancel flag. A triangle covers at most the
// bin's 32x32 pixels, so this bounds the work between looks to well under a millisecond; a sample
// pass (clearing, drawing and shading a bin) counts as this many, so each pass looks once.
constexpr int kTrianglesPerPoll = 256;

// What the z-buffer keeps per pixel: the nearest surface so far. Shading waits until every
// triangle is in (deferred), so each pixel is shaded once however deep the overdraw. The
// interpolated attributes are only valid where `material` is set, so clearing a region touches
// just depth and material.
struct SurfaceAttributes {
  glm::vec3 view_position;
  glm::vec3 world_normal;
  bool front_side;  // the camera sees the triangle's front face (for emission)
};

// What a textured surface adds, kept apart so that the z-buffer's attributes of an untextured
// scene stay small enough for the core's first cache: written only where the material has
// textures.
struct TextureAttributes {
  glm::vec2 uv;        // texture coordinates, perspective-correct
  float uv_per_world;  // the triangle's uv length per view-space length
  glm::vec4 tangent;   // world space, perspective-correct (zero where the mesh has none)
};

// A triangle's uv length per unit of length on it (texture_footprint's measure, the same in
// view and world space, and unchanged by clipping, which keeps the plane and the uv map): the
// square root of its uv area over its area, from its corners in view space.
float uv_per_length(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, glm::vec2 ua, glm::vec2 ub,
                    glm::vec2 uc) {
  const float area = glm::length(glm::cross(b - a, c - a));
  const glm::vec2 e1 = ub - ua, e2 = uc - ua;
  const float uv_area = std::fabs(e1.x * e2.y - e1.y * e2.x);
  const float ratio = area > 0.0f ? std::sqrt(uv_area / area) : 0.0f;
  return std::isfinite(ratio) ? ratio : 0.0f;
}

// Rasterizes the triangles of one bin into one region (a bin, or the part of it inside a tile)
// for one sub-pixel sample position. Owns its z-buffer: no other thread touches these pixels.
class RegionRasterizer {
 public:
  // The buffers start unwritten: begin() clears what a region reads (depth and material), and a
  // pixel's attributes are written with its material, so only those of covered pixels are read.
  // Zeroing them as well took 16,000 instructions a tile (2,040 tiles a frame of the 100-cow grid).
  explicit RegionRasterizer(const RasterFrame& frame) : frame_(frame) {
    constexpr std::size_t kPixels = static_cast<std::size_t>(kBinSize) * kBinSize;
    depth_.allocate(kPixels);
    material_.allocate(kPixels);
    attributes_.allocate(kPixels);
    // Only a frame with textured materials draws textured triangles: one without pays nothing.
    if (frame.textured) texture_attributes_.allocate(kPixels);
  }

  void begin(const Rect& region, FixedPoint sample_offset) {
    region_ = region;
    offset_ = sample_offset;
    const std::size_t n = static_cast<std::size_t>(region.width()) * region.height();
    std::fill_n(depth_.begin(), n, INFINITY);
    std::fill_n(material_.begin(), n, nullptr);
  }

  // The surface seen at a pixel: null where no triangle covers its sample.
  const Material* material(int x, int y) const { return material_[index(x, y)]; }
  const SurfaceAttributes& attributes(int x, int y) const { return attributes_[index(x, y)]; }
  // Only where material() has textures.
  const TextureAttributes& texture_attributes(int x, int y) const { return texture_attributes_[index(x, y)]; }
  std::uint64_t fragments() const { return fragments_; }

  void draw(const ScreenTriangle& t) {
    // Two instances of the loop: an untextured triangle's is the loop as it was before textures,
    // inlined here as it was.
    if (t.material & kTexturedMaterial) {
      draw<true>(t);
    } else {
      draw<false>(t);
    }
  }

 private:
  template <bool kTextured>
  [[gnu::always_inline]] void draw(const ScreenTriangle& t) {
    const ScreenVertex &s0 = frame_.vertex(t.v[0]), &s1 = frame_.vertex(t.v[1]),
                       &s2 = frame_.vertex(t.v[2]);
    const FixedPoint p0 = s0.position.fixed(), p1 = s1.position.fixed(), p2 = s2.position.fixed();
    const int x_begin = std::max({region_.x0, int{t.x0}, first_sample_pixel(std::min({p0.x, p1.x, p2.x}), offset_.x)});
    const int x_end = std::min({region_.x1 - 1, int{t.x1}, last_sample_pixel(std::max({p0.x, p1.x, p2.x}), offset_.x)});
    const int y_begin = std::max({region_.y0, int{t.y0}, first_sample_pixel(std::min({p0.y, p1.y, p2.y}), offset_.y)});
    const int y_end = std::min({region_.y1 - 1, int{t.y1}, last_sample_pixel(std::max({p0.y, p1.y, p2.y}), offset_.y)});
    if (x_begin > x_end || y_begin > y_end) return;

    // Edge i is opposite vertex i, so its value is vertex i's barycentric weight times the area.
    const std::int64_t area = edge_function(p0, p1, p2);
    const std::int64_t bias0 = fill_rule_bias(p1, p2), bias1 = fill_rule_bias(p2, p0),
                       bias2 = fill_rule_bias(p0, p1);
    const std::int64_t step0 = -(p2.y - p1.y) * kSubpixelScale,
                       step1 = -(p0.y - p2.y) * kSubpixelScale,
                       step2 = -(p1.y - p0.y) * kSubpixelScale;
    const float inv_area = 1.0f / static_cast<float>(area);
    const Material* material = frame_.materials[t.material & kMaterialIndex];
    const bool front_side = (t.material & kBackFace) == 0;
    const TextureVertex t0 = kTextured ? frame_.texture_vertex(t.v[0]) : TextureVertex{},
                        t1 = kTextured ? frame_.texture_vertex(t.v[1]) : TextureVertex{},
                        t2 = kTextured ? frame_.texture_vertex(t.v[2]) : TextureVertex{};
    const float uv_per_world =
        kTextured ? uv_per_length(s0.view_position, s1.view_position, s2.view_position, t0.uv, t1.uv, t2.uv) : 0.0f;

    for (int y = y_begin; y <= y_end; ++y) {
      const FixedPoint start{x_begin * kSubpixelScale + offset_.x, y * kSubpixelScale + offset_.y};
      std::int64_t e0 = edge_function(p1, p2, start), e1 = edge_function(p2, p0, start),
                   e2 = edge_function(p0, p1, start);
      for (int x = x_begin; x <= x_end; ++x, e0 += step0, e1 += step1, e2 += step2) {
        if ((e0 + bias0) < 0 || (e1 + bias1) < 0 || (e2 + bias2) < 0) continue;
        ++fragments_;
        const float l0 = static_cast<float>(e0) * inv_area, l1 = static_cast<float>(e1) * inv_area,
                    l2 = static_cast<float>(e2) * inv_area;
        // NDC depth is affine in screen space; attributes are not, so they use 1/w weights.
        const float depth = l0 * s0.ndc_depth + l1 * s1.ndc_depth + l2 * s2.ndc_depth;
        const std::size_t i = index(x, y);
        if (!(depth < depth_[i])) continue;  // ties keep the earlier triangle
        const float q0 = l0 * s0.inv_w, q1 = l1 * s1.inv_w, q2 = l2 * s2.inv_w;
        const float inv_q = 1.0f / (q0 + q1 + q2);
        glm::vec2 uv(0.0f);
        if constexpr (kTextured) {
          uv = (q0 * t0.uv + q1 * t1.uv + q2 * t2.uv) * inv_q;
          // A cut-out fragment leaves the depth as it was: what lies behind shows through.
          if (material->alpha_mode != AlphaMode::Opaque && cut_out(*material, uv, fragment_hash(x, y, depth))) continue;
        }
        depth_[i] = depth;
        material_[i] = material;
        attributes_[i].view_position =
            (q0 * s0.view_position + q1 * s1.view_position + q2 * s2.view_position) * inv_q;
        attributes_[i].world_normal =
            (q0 * s0.world_normal + q1 * s1.world_normal + q2 * s2.world_normal) * inv_q;
        if constexpr (kTextured) {
          texture_attributes_[i].uv = uv;
          texture_attributes_[i].uv_per_world = uv_per_world;
          texture_attributes_[i].tangent = (q0 * t0.tangent + q1 * t1.tangent + q2 * t2.tangent) * inv_q;
        }
        attributes_[i].front_side = front_side;
      }
    }
  }

  // A number uniform in [0, 1) for one fragment at one sample position, so that a blended
  // surface of coverage a covers a share a of a pixel's samples (hashed alpha testing: the
  // rasterizer has no order to blend in; the average over spp samples stands for it). The depth
  // tells the surfaces at one sample apart, and unlike a vertex index it does not depend on how
  // the frame's triangles were set up (clipping, chunks, threads).
  float fragment_hash(int x, int y, float depth) const {
    const auto bits = [](std::int64_t v) { return static_cast<std::uint64_t>(v); };
    std::uint64_t h = mix64((bits(x) << 32) ^ bits(y));
    h = mix64(h ^ (bits(offset_.x) << 32) ^ bits(offset_.y));
    return unit_float(mix64(h ^ std::bit_cast<std::uint32_t>(depth)));
  }

  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y - region_.y0) * static_cast<std::size_t>(region_.width()) +
           static_cast<std::size_t>(x - region_.x0);
  }

  const RasterFrame& frame_;
  Rect region_;
  FixedPoint offset_;
  UninitializedArray<float> depth_;  // NDC depth of the nearest surface so far
  UninitializedArray<const Material*> material_;
  UninitializedArray<SurfaceAttributes> attributes_;
  UninitializedArray<TextureAttributes> texture_attributes_;
  std::uint64_t fragments_ = 0;
};

// Shades the region's visible surfaces, seen from the sample at `offset` in each pixel, and adds
// them to `out`; AOVs come from the first sample.
void shade_region(const RegionRasterizer& raster, const RasterFrame& frame, const Scene& scene,
                  const Rect& region, FixedPoint offset, bool write_aovs, TileBuffer& out) {
  const float pixel_size = scene.camera.pixel_size_at_unit_depth(frame.height);
  const CameraRays camera_rays(scene.camera, frame.width, frame.height);
  Material textured;
  for (int y = region.y0; y < region.y1; ++y) {
    for (int x = region.x0; x < region.x1; ++x) {
      const Material* base = raster.material(x, y);
      glm::vec4& pixel = out.rgba(x, y);
      if (!base) {
        // An environment is seen along the sample's camera ray, as the ray engines see it.
        glm::vec3 background = scene.background;
        if (scene.environment) {
          const float scale = 1.0f / static_cast<float>(kSubpixelScale);
          const Ray ray = camera_rays.ray(static_cast<float>(x) + static_cast<float>(offset.x) * scale,
                                          static_cast<float>(y) + static_cast<float>(offset.y) * scale);
          background = limit_radiance(background_radiance(scene, ray.direction));
        }
        pixel += glm::vec4(background, 0.0f);
        continue;
      }
      const SurfaceAttributes& hit = raster.attributes(x, y);
      const glm::vec3 world = glm::vec3(frame.view_to_world * glm::vec4(hit.view_position, 1.0f));
      const glm::vec3 to_eye = glm::normalize(frame.eye - world);
      const glm::vec3 surface = glm::normalize(hit.world_normal);
      glm::vec3 n = surface;
      const TextureAttributes* texture = base->textures ? &raster.texture_attributes(x, y) : nullptr;
      // A normal map bends the surface's own normal, before the side seen is chosen (as in
      // complete_surface_hit).
      if (texture) n = mapped_normal(*base->textures, texture->uv, n, texture->tangent);
      if (glm::dot(n, to_eye) < 0.0f) {  // two-sided: light the face we see
        n = has_normal_map(*base) ? bent_normal_facing(n, surface, to_eye) : -n;
      }
      // The pixel's footprint as the ray engines' texture_footprint measures it, with the
      // interpolated normal for the triangle's.
      const Material* material = base;
      if (texture) {
        const float footprint =
            pixel_size * -hit.view_position.z / std::max(0.1f, glm::dot(n, to_eye)) * texture->uv_per_world;
        material = &material_at(*base, texture->uv, footprint, textured);
      }
      pixel += glm::vec4(limit_radiance(shade_blinn_phong(*material, world, n, to_eye, hit.front_side, scene.lights,
                                                          ambient_light(scene, *material, n, to_eye))),
                         1.0f);
      if (!write_aovs) continue;
      if (out.aovs().depth) out.depth(x, y) = -hit.view_position.z;
      if (out.aovs().normal) out.normal(x, y) = n;
      if (out.aovs().albedo) out.albedo(x, y) = material->diffuse;
    }
  }
}

// The set-up depends on the image size, and (through culling) on whether only pixel centres
// are sampled.
std::string frame_key(const RenderSettings& settings) {
  return fmt::format("raster {}x{} {}", settings.width, settings.height,
                     settings.spp > 1 ? "supersampled" : "centres");
}

}  // namespace

void prepare_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool,
                   const CancelFlag& cancel) {
  scene.frame_cache().get_or_build<RasterFrame>(
      frame_key(settings), cancel, [&] { return build_raster_frame(scene, settings, &pool, cancel); });
}

StopReason render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                       TileBuffer& out, const CancelFlag& cancel) {
  const auto frame = scene.frame_cache().get_or_build<RasterFrame>(
      frame_key(settings), cancel, [&] { return build_raster_frame(scene, settings, nullptr, cancel); });
  return render_tile_from_frame(*frame, scene, settings, tile, out, cancel);
}

StopReason render_tile_from_frame(const RasterFrame& frame, const PreparedScene& scene,
                                  const RenderSettings& settings, const Rect& requested,
                                  TileBuffer& out, const CancelFlag& cancel) {
  const Rect tile = requested.intersect(Rect{0, 0, frame.width, frame.height});
  // The variance AOV stays at the zeros reset() writes: the rasterizer is deterministic, so its
  // pixel has no Monte Carlo noise to report.
  out.reset(tile, settings.aovs);
  if (tile.empty()) return StopReason::None;
  const int samples = std::max(1, settings.spp);
  RegionRasterizer raster(frame);
  CancelPoll poll(cancel, kTrianglesPerPoll);
  const auto stop = [&] {  // the tile is dropped, never half-written
    out.stats().fragments += raster.fragments();
    out.discard_pixels();
    return cancel.reason();
  };
  for (int by = tile.y0 / kBinSize; by <= (tile.y1 - 1) / kBinSize; ++by) {
    for (int bx = tile.x0 / kBinSize; bx <= (tile.x1 - 1) / kBinSize; ++bx) {
      const Rect region = frame.bin_rect(bx, by).intersect(tile);
      const std::size_t bin = static_cast<std::size_t>(by) * frame.bins_x + bx;
      // One pass per sample position; pass 0 is the pixel centre and also feeds the AOVs.
      for (int s = 0; s < samples; ++s) {
        if (poll(kTrianglesPerPoll)) return stop();
        raster.begin(region, sample_offset(s));
        const std::uint32_t first = frame.bin_start[bin], last = frame.bin_start[bin + 1];
        for (std::uint32_t i = first; i < last; ++i) {
          if (poll()) return stop();
          // The triangles of a bin sit far apart in memory: fetch ahead to hide the latency.
          if (i + 8 < last) __builtin_prefetch(&frame.triangle(frame.bin_triangles[i + 8]));
          if (i + 4 < last) frame.prefetch_vertices(frame.triangle(frame.bin_triangles[i + 4]));
          raster.draw(frame.triangle(frame.bin_triangles[i]));
        }
        shade_region(raster, frame, scene.scene(), region, sample_offset(s), s == 0, out);
      }
    }
  }
  out.stats().fragments += raster.fragments();
  if (samples > 1) {
    const float inv = 1.0f / static_cast<float>(samples);
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) out.rgba(x, y) *= inv;
  }
  return StopReason::None;
}

}  // namespace farm::raster
