#include "tests/support/ray_fixtures.h"

#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>
#include <random>

namespace farm::test {
namespace {

glm::vec3 sphere_direction(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float z = 1.0f - 2.0f * u(rng);
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  const float phi = 2.0f * std::numbers::pi_v<float> * u(rng);
  return {r * std::cos(phi), r * std::sin(phi), z};
}

glm::vec3 point_in(const AABB& b, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  return b.min + glm::vec3(u(rng), u(rng), u(rng)) * b.extent();
}

}  // namespace

std::vector<Ray> random_rays(const AABB& bounds, std::size_t count, std::uint32_t seed,
                             const std::vector<glm::vec3>& planes) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::uniform_int_distribution<int> kind(0, 9), axis_of(0, 5);
  std::uniform_int_distribution<std::size_t> plane_of(0, planes.empty() ? 0 : planes.size() - 1);
  const float radius = std::max(1e-3f, glm::length(bounds.extent()));
  std::vector<Ray> rays;
  rays.reserve(count);
  while (rays.size() < count) {
    Ray ray;
    const int k = kind(rng);
    if (k < 4) {
      ray.origin = point_in(bounds, rng);
      ray.direction = sphere_direction(rng);
    } else if (k < 8) {
      ray.origin = bounds.center() + radius * sphere_direction(rng);
      ray.direction = glm::normalize(point_in(bounds, rng) - ray.origin);
    } else {
      const int a = axis_of(rng);
      glm::vec3 d(0.0f);
      d[a % 3] = a < 3 ? 1.0f : -1.0f;
      ray.direction = d;
      ray.origin = point_in(bounds, rng);
      if (k == 9) ray.origin -= radius * d;  // from outside
      if (!planes.empty() && u(rng) < 0.5f) {
        const int other = (a % 3 + 1 + (u(rng) < 0.5f ? 0 : 1)) % 3;
        ray.origin[other] = planes[plane_of(rng)][other];
      }
    }
    ray.direction *= 0.25f + 3.0f * u(rng);
    rays.push_back(ray);
  }
  return rays;
}

Model random_soup(std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), s(-1.0f, 1.0f);
  Mesh mesh;
  mesh.name = "soup";
  auto add = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const auto base = static_cast<unsigned>(mesh.positions.size());
    glm::vec3 n = glm::cross(b - a, c - a);
    n = glm::length(n) > 0.0f ? glm::normalize(n) : glm::vec3(0.0f, 0.0f, 1.0f);
    for (const glm::vec3& p : {a, b, c}) {
      mesh.positions.push_back(p);
      mesh.normals.push_back(n);
    }
    mesh.triangles.push_back({base, base + 1, base + 2});
  };
  const float planes[] = {-0.5f, 0.0f, 0.25f, 0.75f};
  while (mesh.triangles.size() < count) {
    const int kind = static_cast<int>(u(rng) * 10.0f);
    const glm::vec3 centre{s(rng), s(rng), s(rng)};
    const float size = 0.002f * std::pow(500.0f, u(rng));  // 0.002 .. 1
    glm::vec3 a = centre + size * glm::vec3(s(rng), s(rng), s(rng));
    glm::vec3 b = centre + size * glm::vec3(s(rng), s(rng), s(rng));
    glm::vec3 c = centre + size * glm::vec3(s(rng), s(rng), s(rng));
    if (kind == 0) {
      c = a + (b - a) * u(rng) + 1e-3f * size * glm::vec3(s(rng), s(rng), s(rng));  // sliver
    } else if (kind <= 2) {
      const int axis = kind == 1 ? 1 : static_cast<int>(u(rng) * 3.0f) % 3;  // flat, on a shared plane
      const float p = planes[static_cast<int>(u(rng) * 4.0f) % 4];
      a[axis] = b[axis] = c[axis] = p;
    }
    add(a, b, c);
    if (kind == 3 && mesh.triangles.size() < count) add(a, b, c);  // exact duplicate: t ties
    if (kind == 4) {
      // A strip sharing vertices: hits on shared edges tie.
      for (int i = 0; i < 4 && mesh.triangles.size() < count; ++i) {
        const glm::vec3 d = b + (c - a);
        add(b, d, c);
        a = c;
        c = d;
      }
    }
  }
  Model model;
  model.meshes.push_back(std::move(mesh));
  model.materials.push_back(Material{});
  return model;
}

}  // namespace farm::test
