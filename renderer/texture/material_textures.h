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

struct MaterialTextures {
  TextureSlot base_colour;      // MTL: multiplies kd; glTF: multiplies the base colour
  TextureSlot specular;         // multiplies ks (MTL's map_Ks)
  TextureSlot emission;         // multiplies ke (glTF's emissiveTexture, MTL's map_Ke)
  TextureSlot metal_roughness;  // glTF: blue multiplies metalness, green roughness
  TextureSlot occlusion;        // glTF: red darkens the ambient term, as far as the strength says
  float occlusion_strength = 1.0f;
  TextureSlot opacity;          // MTL's map_d: red is the coverage (1 opaque), for alpha
  TextureSlot normal;           // tangent-space normals (glTF's normalTexture, MTL's norm)
  float normal_scale = 1.0f;    // glTF: scales the map's X and Y
};

// Whether `m` bends its shading normals by a normal map.
inline bool has_normal_map(const Material& m) { return m.textures && m.textures->normal; }

// The shading normal a normal map gives at `uv`: the map's tangent-space normal (its values
// 2 * texel - 1, X and Y times the scale) in the frame of the interpolated `normal` and `tangent`
// (world space; the tangent made perpendicular to the normal first, w its bitangent's side).
// `normal` itself when the material has no normal map or the frame is degenerate.
glm::vec3 mapped_normal(const MaterialTextures& textures, glm::vec2 uv, const glm::vec3& normal,
                        const glm::vec4& tangent);

// How much of the surface `m` covers at `uv` (glTF's alpha: the alpha factor times the base colour
// texture's alpha at its finest level; MTL's map_d: its red instead), and whether a ray or a fragment passes through it there:
// never for an opaque material, below the cutoff for a masked one, and for a blended one where
// the coverage is below `u`, a number uniform in [0, 1) for that ray or fragment (so that a
// surface of coverage a stops a share a of them).
float coverage_at(const Material& m, glm::vec2 uv);
inline bool cut_out(const Material& m, glm::vec2 uv, float u) {
  switch (m.alpha_mode) {
    case AlphaMode::Opaque: return false;
    case AlphaMode::Mask: return coverage_at(m, uv) < m.alpha_cutoff;
    case AlphaMode::Blend: return coverage_at(m, uv) <= u;
  }
  return false;
}

// The material at texture coordinates `uv` with a pixel footprint of `footprint` uv units
// (Texture::sample): `base` itself when it has no textures; else `scratch`, filled with base's
// values and its textures multiplied in, and returned. A metal-roughness material's textures
// multiply its factors, and kd, ks and the shininess are derived again from the product
// (set_metal_roughness); a Phong material's multiply kd and ks.
const Material& material_at(const Material& base, glm::vec2 uv, float footprint, Material& scratch);

}  // namespace farm
