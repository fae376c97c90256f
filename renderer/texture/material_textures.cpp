#include "renderer/texture/material_textures.h"

#include <glm/common.hpp>
#include <glm/vec4.hpp>

namespace farm {

glm::vec4 TextureSlot::sample(glm::vec2 uv, float footprint) const {
  const glm::vec3 moved = transform * glm::vec3(uv, 1.0f);
  return texture->sample(glm::vec2(moved), sampler, footprint);
}

void apply_override(const MaterialOverride& override, Material& m) {
  override.apply_to(m);
  const bool phong_given = override.diffuse || override.specular || override.shininess;
  if (phong_given && m.textures && m.textures->metal_roughness_factors) {
    auto textures = std::make_shared<MaterialTextures>(*m.textures);
    textures->metal_roughness_factors.reset();
    m.textures = std::move(textures);
  }
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
  if (const std::optional<MetalRoughness>& f = t.metal_roughness_factors) {
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
