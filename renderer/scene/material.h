#pragma once
// Phong material as COLLADA and MTL describe it; the path tracer maps it to BSDFs later.
#include <algorithm>
#include <glm/common.hpp>
#include <glm/exponential.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace farm {

// Which faces of an emissive surface shine (docs/architecture.md, "Conventions"). Front: only the side the
// triangle's counter-clockwise winding faces, the side its geometric normal points to, as in
// pbrt's and Mitsuba's area lights. Both: either side (glTF's doubleSided, or a job override).
enum class EmissionSides { Front, Both };

inline std::string_view to_string(EmissionSides s) { return s == EmissionSides::Both ? "both" : "front"; }
inline std::optional<EmissionSides> emission_sides_from_string(std::string_view s) {
  if (s == "front") return EmissionSides::Front;
  if (s == "both") return EmissionSides::Both;
  return std::nullopt;
}

struct MaterialTextures;  // renderer/texture/material_textures.h

// How a material's alpha (its alpha factor times its base colour texture's alpha) covers the
// surface, as glTF's alphaMode says (docs/architecture.md, §8.4): not at all (Opaque, every
// Phong material), all or nothing by the cutoff (Mask), or partly (Blend).
enum class AlphaMode { Opaque, Mask, Blend };

// glTF's metal-roughness values (docs/architecture.md, §8.2): the path tracer shades them with its
// metal-roughness BSDF; the rasterizer and Whitted shade the Phong values set_metal_roughness
// derives from them.
struct MetalRoughness {
  glm::vec3 base_colour{1.0f};
  float metallic = 1.0f;
  float roughness = 1.0f;
};

struct Material {
  std::string name = "default";
  glm::vec3 ambient{1.0f};    // ka
  glm::vec3 diffuse{0.5f};    // kd
  glm::vec3 specular{0.0f};   // ks
  glm::vec3 emission{0.0f};   // ke
  float shininess = 5.0f;     // Phong exponent p
  float ior = 1.33f;
  float transmission = 0.0f;  // 0 opaque, 1 fully transmissive (MTL 1-d, glTF transmission)
  // Set for glTF's materials (with ior the dielectric's index); unset for Phong ones.
  std::optional<MetalRoughness> metal_roughness;
  AlphaMode alpha_mode = AlphaMode::Opaque;
  float alpha = 1.0f;          // glTF: baseColorFactor's fourth value
  float alpha_cutoff = 0.5f;   // Mask: covered where alpha >= this
  EmissionSides emission_sides = EmissionSides::Front;
  // What multiplies these values at a surface point (material_at); null for a material without
  // textures. New shading values must be copied by material_at too.
  std::shared_ptr<const MaterialTextures> textures;

  // Shininess this high means a perfect mirror (docs/architecture.md, "Conventions").
  bool is_mirror() const { return shininess >= 1000.0f; }

  // The share of the surface that is glass (docs/architecture.md, §8.2): its transmission
  // (with an ior above 1), less glTF's metallic part, since metals let nothing through. The
  // engines shade the rest as they would the same material without transmission.
  float transmitted_share() const {
    if (!(transmission > 0.0f && ior > 1.0f)) return 0.0f;
    const float t = std::min(transmission, 1.0f);
    if (!metal_roughness) return t;
    return t * (1.0f - glm::clamp(metal_roughness->metallic, 0.0f, 1.0f));
  }
  // What light passing through that glass keeps at each crossing: glTF tints it by the base
  // colour, which a ray through a closed object gets over its two crossings; Phong glass is clear.
  glm::vec3 transmission_tint() const {
    return metal_roughness ? glm::sqrt(glm::clamp(metal_roughness->base_colour, 0.0f, 1.0f)) : glm::vec3(1.0f);
  }

  // The radiance emitted towards a viewer on the front side of the surface (`front_side`: the
  // viewer lies where the geometric normal points) or on its back side.
  glm::vec3 emitted(bool front_side) const {
    return front_side || emission_sides == EmissionSides::Both ? emission : glm::vec3(0.0f);
  }
};

// glTF's metal-roughness values, kept for the path tracer, and their Phong counterpart for the
// other engines (docs/architecture.md, §8.2): metals have no diffuse lobe and tint their
// reflection, dielectrics reflect about 4% at normal incidence. The Blinn-Phong exponent whose
// lobe is as wide as a Beckmann lobe of slope alpha is 2 / alpha^2 - 2 (Walter et al. 2007), and
// glTF's alpha is roughness^2: roughness below about 0.21 reaches 1000 and so becomes a mirror in
// the rasterizer and Whitted, as our material convention intends.
inline void set_metal_roughness(Material& m, const glm::vec3& base, float metallic, float roughness) {
  m.metal_roughness = MetalRoughness{base, metallic, roughness};
  m.diffuse = base * (1.0f - metallic);
  m.specular = glm::mix(glm::vec3(0.04f), base, metallic);
  const float r4 = roughness * roughness * roughness * roughness;
  m.shininess = r4 > 0.0f ? glm::clamp(2.0f / r4 - 2.0f, 1.0f, 10000.0f) : 10000.0f;
}

// The keys a job gives under `objects[i].material`; only those present replace the file's values.
struct MaterialOverride {
  std::optional<glm::vec3> ambient, diffuse, specular, emission;
  std::optional<float> shininess, ior, transmission;
  std::optional<EmissionSides> emission_sides;

  // A job that gives kd, ks or the shininess asks for that Phong material: a glTF material it is
  // given to stops being a metal-roughness one (and its textures multiply the values given).
  void apply_to(Material& m) const {
    if (diffuse || specular || shininess) m.metal_roughness.reset();
    if (ambient) m.ambient = *ambient;
    if (diffuse) m.diffuse = *diffuse;
    if (specular) m.specular = *specular;
    if (emission) m.emission = *emission;
    if (shininess) m.shininess = *shininess;
    if (ior) m.ior = *ior;
    if (transmission) m.transmission = *transmission;
    if (emission_sides) m.emission_sides = *emission_sides;
  }
  bool empty() const {
    return !ambient && !diffuse && !specular && !emission && !shininess && !ior && !transmission &&
           !emission_sides;
  }
};

}  // namespace farm
