#include "renderer/raster/raster_engine.h"

#include <algorithm>
#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <vector>

#include "renderer/raster/clip_polygon.h"
#include "renderer/raster/edge_function.h"
#include "renderer/raster/sample_pattern.h"
#include "renderer/scene/blinn_phong.h"

namespace farm::raster {
namespace {

// What the z-buffer keeps per pixel: the nearest surface so far. Shading waits until every
// triangle is in (deferred), so each pixel is shaded once however deep the overdraw.
struct SurfaceSample {
  float ndc_depth = INFINITY;
  glm::vec3 view_position{0.0f};
  glm::vec3 world_normal{0.0f};
  const Material* material = nullptr;
};

struct FrameTransforms {
  glm::mat4 view;
  glm::mat4 view_projection;
  glm::mat4 view_to_world;
  glm::vec3 eye;
  float width, height;
};

class TileRasterizer {
 public:
  TileRasterizer(const FrameTransforms& frame, const Rect& tile, FixedPoint sample_offset)
      : frame_(frame), tile_(tile), offset_(sample_offset),
        samples_(static_cast<std::size_t>(tile.width()) * static_cast<std::size_t>(tile.height())) {}

  void draw_object(const PreparedObject& object) {
    const SceneObject& source = *object.source;
    const glm::mat4 to_clip = frame_.view_projection * object.model_to_world;
    const glm::mat4 to_view = frame_.view * object.model_to_world;
    for (const Mesh& mesh : source.model->meshes) {
      const Material* material = &source.materials.at(mesh.material);
      // Vertex stage: positions to clip and view space, normals to world space.
      vertices_.resize(mesh.positions.size());
      for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec4 p(mesh.positions[i], 1.0f);
        ClipVertex& v = vertices_[i];
        v.clip = to_clip * p;
        v.view_position = glm::vec3(to_view * p);
        const glm::vec3 n = object.normal_to_world * mesh.normals[i];
        const float len = glm::length(n);
        v.world_normal = len > 0.0f ? n / len : n;
      }
      for (const glm::uvec3& t : mesh.triangles) {
        draw_triangle(vertices_[t.x], vertices_[t.y], vertices_[t.z], material);
      }
    }
  }

  const SurfaceSample& sample(int x, int y) const {
    return samples_[static_cast<std::size_t>(y - tile_.y0) * static_cast<std::size_t>(tile_.width()) +
                    static_cast<std::size_t>(x - tile_.x0)];
  }

 private:
  struct ScreenVertex {
    FixedPoint position;
    float ndc_depth;
    float inv_w;
    const ClipVertex* attributes;
  };

  void draw_triangle(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c,
                     const Material* material) {
    if (trivially_outside(a.clip, b.clip, c.clip)) return;
    if (trivially_inside(a.clip, b.clip, c.clip)) {
      rasterize(a, b, c, material);
      return;
    }
    const ClippedPolygon poly = clip_triangle(a, b, c);
    for (std::size_t i = 2; i < poly.size; ++i) {
      rasterize(poly.vertices[0], poly.vertices[i - 1], poly.vertices[i], material);
    }
  }

  ScreenVertex to_screen(const ClipVertex& v) const {
    const float inv_w = 1.0f / v.clip.w;  // w >= near > 0 after clipping
    const float ndc_x = v.clip.x * inv_w, ndc_y = v.clip.y * inv_w;
    return {{to_fixed((ndc_x * 0.5f + 0.5f) * frame_.width),
             to_fixed((0.5f - ndc_y * 0.5f) * frame_.height)},
            v.clip.z * inv_w, inv_w, &v};
  }

  // Pixel index range whose sample points (pixel * 256 + offset) lie in [lo, hi].
  static int first_pixel(std::int64_t lo, std::int64_t offset) {
    const std::int64_t n = lo - offset;
    return static_cast<int>(n >= 0 ? (n + kSubpixelScale - 1) / kSubpixelScale : -((-n) / kSubpixelScale));
  }
  static int last_pixel(std::int64_t hi, std::int64_t offset) {
    const std::int64_t n = hi - offset;
    return static_cast<int>(n >= 0 ? n / kSubpixelScale : -((-n + kSubpixelScale - 1) / kSubpixelScale));
  }

  void rasterize(const ClipVertex& va, const ClipVertex& vb, const ClipVertex& vc,
                 const Material* material) {
    ScreenVertex s0 = to_screen(va), s1 = to_screen(vb), s2 = to_screen(vc);
    std::int64_t area = edge_function(s0.position, s1.position, s2.position);
    if (area == 0) return;  // degenerate on the sample grid: covers no sample
    if (area < 0) {         // either winding is drawn: orient it positively
      std::swap(s1, s2);
      area = -area;
    }
    const FixedPoint &p0 = s0.position, &p1 = s1.position, &p2 = s2.position;
    const int x_begin = std::max(tile_.x0, first_pixel(std::min({p0.x, p1.x, p2.x}), offset_.x));
    const int x_end = std::min(tile_.x1 - 1, last_pixel(std::max({p0.x, p1.x, p2.x}), offset_.x));
    const int y_begin = std::max(tile_.y0, first_pixel(std::min({p0.y, p1.y, p2.y}), offset_.y));
    const int y_end = std::min(tile_.y1 - 1, last_pixel(std::max({p0.y, p1.y, p2.y}), offset_.y));
    if (x_begin > x_end || y_begin > y_end) return;

    // Edge i is opposite vertex i, so its value is vertex i's barycentric weight times `area`.
    const std::int64_t bias0 = fill_rule_bias(p1, p2), bias1 = fill_rule_bias(p2, p0),
                       bias2 = fill_rule_bias(p0, p1);
    const std::int64_t step0 = -(p2.y - p1.y) * kSubpixelScale,
                       step1 = -(p0.y - p2.y) * kSubpixelScale,
                       step2 = -(p1.y - p0.y) * kSubpixelScale;
    const float inv_area = 1.0f / static_cast<float>(area);

    for (int y = y_begin; y <= y_end; ++y) {
      const FixedPoint start{x_begin * kSubpixelScale + offset_.x, y * kSubpixelScale + offset_.y};
      std::int64_t e0 = edge_function(p1, p2, start), e1 = edge_function(p2, p0, start),
                   e2 = edge_function(p0, p1, start);
      for (int x = x_begin; x <= x_end; ++x, e0 += step0, e1 += step1, e2 += step2) {
        if ((e0 + bias0) < 0 || (e1 + bias1) < 0 || (e2 + bias2) < 0) continue;
        const float l0 = static_cast<float>(e0) * inv_area, l1 = static_cast<float>(e1) * inv_area,
                    l2 = static_cast<float>(e2) * inv_area;
        // NDC depth is affine in screen space; attributes are not, so they use 1/w weights.
        const float depth = l0 * s0.ndc_depth + l1 * s1.ndc_depth + l2 * s2.ndc_depth;
        SurfaceSample& target = samples_[static_cast<std::size_t>(y - tile_.y0) *
                                             static_cast<std::size_t>(tile_.width()) +
                                         static_cast<std::size_t>(x - tile_.x0)];
        if (!(depth < target.ndc_depth)) continue;  // ties keep the earlier triangle
        const float q0 = l0 * s0.inv_w, q1 = l1 * s1.inv_w, q2 = l2 * s2.inv_w;
        const float inv_q = 1.0f / (q0 + q1 + q2);
        target.ndc_depth = depth;
        target.view_position = (q0 * s0.attributes->view_position + q1 * s1.attributes->view_position +
                                q2 * s2.attributes->view_position) * inv_q;
        target.world_normal = (q0 * s0.attributes->world_normal + q1 * s1.attributes->world_normal +
                               q2 * s2.attributes->world_normal) * inv_q;
        target.material = material;
      }
    }
  }

  const FrameTransforms& frame_;
  Rect tile_;
  FixedPoint offset_;
  std::vector<SurfaceSample> samples_;
  std::vector<ClipVertex> vertices_;
};

FrameTransforms frame_transforms(const Camera& camera, const RenderSettings& settings) {
  FrameTransforms f;
  f.view = camera.view_matrix();
  f.view_projection = camera.projection_matrix(camera.aspect_for(settings.width, settings.height)) * f.view;
  f.view_to_world = glm::inverse(f.view);
  f.eye = camera.position;
  f.width = static_cast<float>(settings.width);
  f.height = static_cast<float>(settings.height);
  return f;
}

}  // namespace

void render_tile(const PreparedScene& prepared, const RenderSettings& settings, const Rect& tile,
                 TileBuffer& out) {
  out.reset(tile, settings.aovs);
  if (tile.empty()) return;
  const Scene& scene = prepared.scene();
  const FrameTransforms frame = frame_transforms(scene.camera, settings);
  const int samples = std::max(1, settings.spp);

  for (int s = 0; s < samples; ++s) {
    // One full pass per sample position; pass 0 is the pixel centre and also feeds the AOVs.
    TileRasterizer rasterizer(frame, tile, sample_offset(s));
    for (const PreparedObject& object : prepared.objects()) rasterizer.draw_object(object);

    const bool write_aovs = s == 0;
    for (int y = tile.y0; y < tile.y1; ++y) {
      for (int x = tile.x0; x < tile.x1; ++x) {
        const SurfaceSample& hit = rasterizer.sample(x, y);
        glm::vec4& pixel = out.rgba(x, y);
        if (!hit.material) {
          pixel += glm::vec4(scene.background, 0.0f);
          continue;
        }
        const glm::vec3 world = glm::vec3(frame.view_to_world * glm::vec4(hit.view_position, 1.0f));
        const glm::vec3 to_eye = glm::normalize(frame.eye - world);
        glm::vec3 n = glm::normalize(hit.world_normal);
        if (glm::dot(n, to_eye) < 0.0f) n = -n;  // two-sided: light the face we see
        const glm::vec3 color =
            shade_blinn_phong(*hit.material, world, n, to_eye, scene.lights, scene.ambient);
        pixel += glm::vec4(color, 1.0f);
        if (!write_aovs) continue;
        if (out.aovs().depth) out.depth(x, y) = -hit.view_position.z;
        if (out.aovs().normal) out.normal(x, y) = n;
        if (out.aovs().albedo) out.albedo(x, y) = hit.material->diffuse;
      }
    }
  }
  if (samples > 1) {
    const float inv = 1.0f / static_cast<float>(samples);
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) out.rgba(x, y) *= inv;
  }
}

}  // namespace farm::raster
