#include "renderer/texture/material_textures.h"

#include <glm/common.hpp>
#include <glm/vec4.hpp>

namespace farm {

glm::vec4 TextureSlot::sample(glm::vec2 uv, float footprint) const {
  const glm::vec3 moved = transform * glm::vec3(uv, 1.0f);
  return texture->sample(glm::vec2(moved), sampler, footprint);
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
  if (t.base_colour) {
    const glm::vec3 colour(t.base_colour.sample(uv, footprint));
    scratch.diffuse *= colour;
    scratch.specular *= glm::mix(glm::vec3(1.0f), colour, t.metallic);
  }
  if (t.specular) scratch.specular *= glm::vec3(t.specular.sample(uv, footprint));
  if (t.emission) scratch.emission *= glm::vec3(t.emission.sample(uv, footprint));
  return scratch;
}

}  // namespace farm
