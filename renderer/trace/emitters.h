#pragma once
// The scene's emissive triangles as area lights, in world space, chosen with probability
// proportional to their power (luminance of the emitted radiance times area) and sampled
// uniformly by area. A triangle shines from its front face (where its geometric normal points)
// unless its material says both (Material::emission_sides); the choice of triangles ignores the
// side, so a point picked on the back of a front-only emitter simply contributes nothing. An
// emission texture is read at the point picked; the choice weighs its triangle by the texture's
// mean (its last mip level), and stays unbiased however the texture varies across it.
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

namespace farm {

class PreparedScene;
struct Material;

struct EmitterSample {
  glm::vec3 position{0.0f};
  glm::vec3 normal{0.0f};     // unit, world: the geometric normal, the front side
  glm::vec3 radiance{0.0f};   // emitted radiance Le
  bool two_sided = false;     // shines from the back too
  float pdf_area = 0.0f;      // density of this point per unit area (choice included)
};

// The index of the first entry of `sorted` (ascending) greater than `value`, sorted.size() if
// none: std::upper_bound's answer, found without data-dependent branches.
std::size_t first_above(std::span<const float> sorted, float value);

class Emitters {
 public:
  explicit Emitters(const PreparedScene& scene);

  bool empty() const { return triangles_.empty(); }
  std::size_t size() const { return triangles_.size(); }

  // A point on the emitters for uniform numbers u_pick, u1, u2 in [0, 1).
  EmitterSample sample(float u_pick, float u1, float u2) const;

  // Density per unit area with which sample() produces a point on (object, triangle); 0 if
  // that triangle does not emit.
  float pdf_area(std::uint32_t object, std::uint32_t triangle) const;

 private:
  struct Triangle {
    glm::vec3 p0, e1, e2;  // world corner and edges
    glm::vec3 normal;
    glm::vec3 radiance;
    float area;
    bool two_sided;
    const Material* textured = nullptr;  // the material, when its emission has a texture
    glm::vec2 uv0{0.0f}, uv1{0.0f}, uv2{0.0f};
  };
  std::vector<Triangle> triangles_;
  std::vector<float> cdf_;  // cdf_[i] = P(pick <= i)
  // Per triangle, the density per unit area of a point sample() makes there: its chance of being
  // picked over its area, divided once here rather than at every sample.
  std::vector<float> pdf_area_;
  std::unordered_map<std::uint64_t, std::uint32_t> index_of_;  // (object << 32 | triangle) -> i
};

}  // namespace farm
