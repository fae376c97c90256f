#pragma once
// The textures a material's values are multiplied by (docs/architecture.md, "Textures"), and the
// material an engine shades with at a surface point. A material without textures (every Phong
// material of COLLADA and MTL files that name no maps) is shaded as it is, with no copy and no
// other arithmetic, so its pixels do not change.
#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <memory>

#include "renderer/scene/material.h"
#include "renderer/texture/texture.h"

namespace farm {

// One texture as a material uses it: the image, its sampler and glTF's KHR_texture_transform.
struct TextureSlot {
  std::shared_ptr<const Texture> texture;  // null: the slot is empty
  TextureSampler sampler;
  glm::mat3 transform{1.0f};

  explicit operator bool() const { return texture != nullptr; }
  glm::vec4 sample(glm::vec2 uv, float footprint) const;
};

struct MaterialTextures {
  TextureSlot base_colour;  // multiplies kd, and ks as far as the material is metal
  TextureSlot specular;     // multiplies ks (MTL's map_Ks)
  TextureSlot emission;     // multiplies ke (glTF's emissiveTexture, MTL's map_Ke)
  float metallic = 0.0f;    // glTF: a metal's ks is its base colour, so the base colour tints it
};

// The material at texture coordinates `uv` with a pixel footprint of `footprint` uv units
// (Texture::sample): `base` itself when it has no textures; else `scratch`, filled with base's
// values and its textures multiplied in, and returned.
const Material& material_at(const Material& base, glm::vec2 uv, float footprint, Material& scratch);

}  // namespace farm
