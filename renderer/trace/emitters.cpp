#include "renderer/trace/emitters.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

#include "renderer/accel/prepared_scene.h"
#include "renderer/texture/material_textures.h"
#include "renderer/trace/sample_warp.h"

namespace farm {
namespace {

float luminance(const glm::vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

}  // namespace

Emitters::Emitters(const PreparedScene& scene) {
  std::vector<float> power;
  for (std::uint32_t o = 0; o < scene.objects().size(); ++o) {
    const PreparedObject& object = scene.objects()[o];
    const ModelTriangles& mesh = *object.triangles;
    for (std::uint32_t t = 0; t < mesh.size(); ++t) {
      const Material& material = object.source->materials[mesh.material[t]];
      // Without texture coordinates every point reads the texture at uv (0, 0), as hits do.
      const bool textured = material.textures && material.textures->emission;
      glm::vec3 le = material.emission;
      if (textured) {
        const Texture& texture = *material.textures->emission.texture;
        le *= glm::vec3(texture.texel(texture.levels() - 1, 0, 0));
      }
      // Non-finite emission (possible only in scenes built in code) is not sampled: it would
      // poison the whole table; paths that hit it are dropped and counted by the engine.
      const float l = luminance(le);
      if (!(l > 0.0f) || !std::isfinite(l)) continue;
      const glm::uvec3& tri = mesh.triangles[t];
      const auto world = [&](std::uint32_t i) {
        return glm::vec3(object.model_to_world * glm::vec4(mesh.positions[i], 1.0f));
      };
      Triangle w;
      w.p0 = world(tri.x);
      w.e1 = world(tri.y) - w.p0;
      w.e2 = world(tri.z) - w.p0;
      w.area = 0.5f * glm::length(glm::cross(w.e1, w.e2));
      if (!(w.area > 0.0f)) continue;
      // The front as a hit on this triangle sees it (complete_surface_hit): the model's winding
      // normal carried by the inverse transpose, which keeps it on the same side of the surface
      // under a mirroring transform (the world edges' cross product would flip there).
      w.normal = glm::normalize(object.normal_to_world * mesh.face_normals[t]);
      if (!std::isfinite(w.normal.x)) continue;
      w.radiance = le;
      w.two_sided = material.emission_sides == EmissionSides::Both;
      if (textured) {
        w.textured = &material;
        if (!mesh.uvs.empty()) {
          w.uv0 = mesh.uvs[tri.x];
          w.uv1 = mesh.uvs[tri.y];
          w.uv2 = mesh.uvs[tri.z];
        }
      }
      index_of_[(std::uint64_t{o} << 32) | t] = static_cast<std::uint32_t>(triangles_.size());
      triangles_.push_back(w);
      power.push_back(l * w.area);
    }
  }
  double total = 0.0;
  for (float p : power) total += p;
  double running = 0.0;
  for (std::size_t i = 0; i < power.size(); ++i) {
    running += power[i];
    cdf_.push_back(static_cast<float>(running / total));
    pdf_area_.push_back(static_cast<float>(power[i] / total) / triangles_[i].area);
  }
  if (!cdf_.empty()) cdf_.back() = 1.0f;
}

std::size_t first_above(std::span<const float> sorted, float value) {
  // Halve the range by moves the compiler makes conditional (cmov), not branches: the pick is a
  // fresh random number each time, so a branch per step was mispredicted half the time (half of
  // this sampler's time on the Cornell box, by perf, for its two-triangle lamp).
  if (sorted.empty()) return 0;
  std::size_t base = 0, n = sorted.size();
  while (n > 1) {
    const std::size_t half = n / 2;
    base = sorted[base + half - 1] <= value ? base + half : base;
    n -= half;
  }
  return base + (sorted[base] <= value ? 1 : 0);
}

EmitterSample Emitters::sample(float u_pick, float u1, float u2) const {
  const std::size_t i = std::min(first_above(cdf_, u_pick), cdf_.size() - 1);
  const Triangle& t = triangles_[i];
  const glm::vec2 w = uniform_triangle_weights(u1, u2);
  const float b1 = w.x, b2 = w.y;
  EmitterSample out;
  out.position = t.p0 + b1 * t.e1 + b2 * t.e2;
  out.normal = t.normal;
  out.radiance = t.radiance;
  if (t.textured) {
    const glm::vec2 uv = (1.0f - b1 - b2) * t.uv0 + b1 * t.uv1 + b2 * t.uv2;
    out.radiance = t.textured->emission * glm::vec3(t.textured->textures->emission.sample(uv, 0.0f));
  }
  out.two_sided = t.two_sided;
  out.pdf_area = pdf_area_[i];
  return out;
}

float Emitters::pdf_area(std::uint32_t object, std::uint32_t triangle) const {
  const auto it = index_of_.find((std::uint64_t{object} << 32) | triangle);
  if (it == index_of_.end()) return 0.0f;
  return pdf_area_[it->second];
}

}  // namespace farm
