#pragma once
// Phong material as COLLADA and MTL describe it; the path tracer maps it to BSDFs later.
#include <glm/vec3.hpp>
#include <optional>
#include <string>

namespace farm {

struct Material {
  std::string name = "default";
  glm::vec3 ambient{1.0f};    // ka
  glm::vec3 diffuse{0.5f};    // kd
  glm::vec3 specular{0.0f};   // ks
  glm::vec3 emission{0.0f};   // ke
  float shininess = 5.0f;     // Phong exponent p
  float ior = 1.33f;
  float transmission = 0.0f;  // 0 opaque, 1 fully transmissive (MTL 1-d, glTF transmission)

  // Shininess this high means a perfect mirror (DESIGN.md conventions).
  bool is_mirror() const { return shininess >= 1000.0f; }
};

// The keys a job gives under `objects[i].material`; only those present replace the file's values.
struct MaterialOverride {
  std::optional<glm::vec3> ambient, diffuse, specular, emission;
  std::optional<float> shininess, ior, transmission;

  void apply_to(Material& m) const {
    if (ambient) m.ambient = *ambient;
    if (diffuse) m.diffuse = *diffuse;
    if (specular) m.specular = *specular;
    if (emission) m.emission = *emission;
    if (shininess) m.shininess = *shininess;
    if (ior) m.ior = *ior;
    if (transmission) m.transmission = *transmission;
  }
  bool empty() const {
    return !ambient && !diffuse && !specular && !emission && !shininess && !ior && !transmission;
  }
};

}  // namespace farm
