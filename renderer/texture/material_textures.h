#pragma once
// The textures a material's values are multiplied by (docs/architecture.md, "Textures"), and the
// material an engine shades with at a surface point. A material without textures (every Phong
// material of COLLADA and MTL files that name no maps) is shaded as it is, with no copy and no
// other arithmetic, so its pixels do not change.
#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <memory>
#include <optional>

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

// A glTF material's factors, which its textures multiply before the product is mapped to Phong
// (set_metal_roughness).
struct MetalRoughness {
  glm::vec3 base_colour{1.0f};
  float metallic = 1.0f;
  float roughness = 1.0f;
};

struct MaterialTextures {
  TextureSlot base_colour;      // MTL: multiplies kd; glTF: the base colour
  TextureSlot specular;         // multiplies ks (MTL's map_Ks)
  TextureSlot emission;         // multiplies ke (glTF's emissiveTexture, MTL's map_Ke)
  TextureSlot metal_roughness;  // glTF: blue multiplies metalness, green roughness
  TextureSlot occlusion;        // glTF: red darkens the ambient term, as far as the strength says
  float occlusion_strength = 1.0f;
  TextureSlot normal;           // tangent-space normals (glTF's normalTexture, MTL's norm)
  float normal_scale = 1.0f;    // glTF: scales the map's X and Y
  // glTF: kd, ks and the shininess are the metal-roughness mapping of the factors times the
  // textures, worked out again at each point. Unset (MTL): the textures multiply kd and ks.
  std::optional<MetalRoughness> metal_roughness_factors;
};

// A job's override on a material that may have textures: the keys it gives replace the file's
// values, and a glTF material whose kd, ks or shininess it replaces stops deriving them from its
// factors, so that its textures multiply the values the job gave (as MTL's do).
void apply_override(const MaterialOverride& override, Material& m);

// Whether `m` bends its shading normals by a normal map.
inline bool has_normal_map(const Material& m) { return m.textures && m.textures->normal; }

// The shading normal a normal map gives at `uv`: the map's tangent-space normal (its values
// 2 * texel - 1, X and Y times the scale) in the frame of the interpolated `normal` and `tangent`
// (world space; the tangent made perpendicular to the normal first, w its bitangent's side).
// `normal` itself when the material has no normal map or the frame is degenerate.
glm::vec3 mapped_normal(const MaterialTextures& textures, glm::vec2 uv, const glm::vec3& normal,
                        const glm::vec4& tangent);

// The material at texture coordinates `uv` with a pixel footprint of `footprint` uv units
// (Texture::sample): `base` itself when it has no textures; else `scratch`, filled with base's
// values and its textures multiplied in, and returned.
const Material& material_at(const Material& base, glm::vec2 uv, float footprint, Material& scratch);

}  // namespace farm
