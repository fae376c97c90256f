#include "renderer/texture/material_textures.h"

#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

namespace farm {

glm::vec4 TextureSlot::sample(glm::vec2 uv, float footprint) const {
  const glm::vec3 moved = transform * glm::vec3(uv, 1.0f);
  return texture->sample(glm::vec2(moved), sampler, footprint);
}

glm::vec3 mapped_normal(const MaterialTextures& textures, glm::vec2 uv, const glm::vec3& normal,
                        const glm::vec4& tangent) {
  if (!textures.normal) return normal;
  const glm::vec3 t = glm::vec3(tangent) - normal * glm::dot(normal, glm::vec3(tangent));
  const float t_length = glm::length(t);
  if (!(t_length > 0.0f) || !std::isfinite(t_length)) return normal;
  const glm::vec3 unit_t = t / t_length;
  const glm::vec3 b = (tangent.w < 0.0f ? -1.0f : 1.0f) * glm::cross(normal, unit_t);
  const glm::vec3 texel(textures.normal.sample(uv, 0.0f));
  const glm::vec3 local = (2.0f * texel - 1.0f) * glm::vec3(textures.normal_scale, textures.normal_scale, 1.0f);
  const glm::vec3 mapped = local.x * unit_t + local.y * b + local.z * normal;
  const float length = glm::length(mapped);
  return length > 0.0f && std::isfinite(length) ? mapped / length : normal;
}

float coverage_at(const Material& m, glm::vec2 uv) {
  if (!m.textures) return m.alpha;
  if (m.textures->opacity) return m.alpha * m.textures->opacity.sample(uv, 0.0f).x;
  if (m.textures->base_colour) return m.alpha * m.textures->base_colour.sample(uv, 0.0f).w;
  return m.alpha;
}

const Material& material_at(const Material& base, glm::vec2 uv, float footprint, Material& scratch) {
  if (!base.textures) return base;
  const MaterialTextures& t = *base.textures;
  // The shading values only: the name and the textures are not read by engines, and copying them
  // per hit would cost an allocation and an atomic count.
  scratch.ambient = base.ambient;
  scratch.diffuse = base.diffuse;
  scratch.specular = base.specular;
  scratch.emission = base.emission;
  scratch.shininess = base.shininess;
  scratch.ior = base.ior;
  scratch.transmission = base.transmission;
  scratch.emission_sides = base.emission_sides;
  scratch.metal_roughness = base.metal_roughness;
  scratch.alpha_mode = base.alpha_mode;
  scratch.alpha = base.alpha;
  scratch.alpha_cutoff = base.alpha_cutoff;
  if (const std::optional<MetalRoughness>& f = base.metal_roughness) {
    glm::vec3 colour = f->base_colour;
    float metallic = f->metallic, roughness = f->roughness;
    if (t.base_colour) colour *= glm::vec3(t.base_colour.sample(uv, footprint));
    if (t.metal_roughness) {
      const glm::vec4 texel = t.metal_roughness.sample(uv, footprint);
      metallic = glm::clamp(metallic * texel.z, 0.0f, 1.0f);
      roughness = glm::clamp(roughness * texel.y, 0.0f, 1.0f);
    }
    set_metal_roughness(scratch, colour, metallic, roughness);
  } else if (t.base_colour) {
    scratch.diffuse *= glm::vec3(t.base_colour.sample(uv, footprint));
  }
  if (t.occlusion) {
    const float occluded = t.occlusion.sample(uv, footprint).x;
    scratch.ambient *= 1.0f + t.occlusion_strength * (occluded - 1.0f);
  }
  if (t.specular) scratch.specular *= glm::vec3(t.specular.sample(uv, footprint));
  if (t.emission) scratch.emission *= glm::vec3(t.emission.sample(uv, footprint));
  return scratch;
}

}  // namespace farm
