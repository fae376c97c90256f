#include "tests/support/scene_fixtures.h"

#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>

#include "renderer/engine.h"
#include "renderer/scene/transform.h"

namespace farm::test {

Model make_quad(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
  Mesh mesh;
  mesh.name = "quad";
  mesh.positions = {a, b, c, d};
  const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
  mesh.normals = {n, n, n, n};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  Model model;
  model.meshes.push_back(mesh);
  model.materials.push_back(Material{});
  return model;
}

Model make_box(glm::vec3 lo, glm::vec3 hi) {
  Mesh mesh;
  mesh.name = "box";
  auto face = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
    const auto base = static_cast<unsigned>(mesh.positions.size());
    const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
    for (const glm::vec3& p : {a, b, c, d}) {
      mesh.positions.push_back(p);
      mesh.normals.push_back(n);
    }
    mesh.triangles.push_back({base, base + 1, base + 2});
    mesh.triangles.push_back({base, base + 2, base + 3});
  };
  const glm::vec3 p000{lo.x, lo.y, lo.z}, p100{hi.x, lo.y, lo.z}, p010{lo.x, hi.y, lo.z},
      p110{hi.x, hi.y, lo.z}, p001{lo.x, lo.y, hi.z}, p101{hi.x, lo.y, hi.z},
      p011{lo.x, hi.y, hi.z}, p111{hi.x, hi.y, hi.z};
  face(p001, p101, p111, p011);  // +z
  face(p100, p000, p010, p110);  // -z
  face(p101, p100, p110, p111);  // +x
  face(p000, p001, p011, p010);  // -x
  face(p011, p111, p110, p010);  // +y
  face(p000, p100, p101, p001);  // -y
  Model model;
  model.meshes.push_back(mesh);
  model.materials.push_back(Material{});
  return model;
}

Model make_grid(int n) {
  Mesh mesh;
  mesh.name = "grid";
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.positions.push_back({-1.0f + 2.0f * static_cast<float>(i) / static_cast<float>(n),
                                -1.0f + 2.0f * static_cast<float>(j) / static_cast<float>(n), 0.0f});
      mesh.normals.push_back({0.0f, 0.0f, 1.0f});
    }
  }
  const auto at = [n](int i, int j) { return static_cast<unsigned>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      // Alternate the diagonal so edges run in several directions.
      if ((i + j) % 2 == 0) {
        mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      } else {
        mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        mesh.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  Model model;
  model.meshes.push_back(mesh);
  model.materials.push_back(Material{});
  return model;
}

Model make_sphere(int rings, int segments) {
  Mesh mesh;
  mesh.name = "sphere";
  const float pi = std::numbers::pi_v<float>;
  for (int r = 0; r <= rings; ++r) {
    const float theta = pi * static_cast<float>(r) / static_cast<float>(rings);
    for (int s = 0; s <= segments; ++s) {
      const float phi = 2.0f * pi * static_cast<float>(s) / static_cast<float>(segments);
      const glm::vec3 p{std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
      mesh.positions.push_back(p);
      mesh.normals.push_back(p);
    }
  }
  const auto at = [segments](int r, int s) { return static_cast<unsigned>(r * (segments + 1) + s); };
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      if (r != 0) mesh.triangles.push_back({at(r, s), at(r, s + 1), at(r + 1, s)});
      if (r != rings - 1) mesh.triangles.push_back({at(r, s + 1), at(r + 1, s + 1), at(r + 1, s)});
    }
  }
  Model model;
  model.meshes.push_back(mesh);
  model.materials.push_back(Material{});
  return model;
}

glm::mat4 placed(glm::vec3 translate, glm::vec3 axis, float degrees, glm::vec3 scale) {
  ObjectTransform transform;
  transform.translate = translate;
  transform.rotate_axis = axis;
  transform.rotate_degrees = degrees;
  transform.scale = scale;
  return transform.matrix();
}

SceneObject object_of(Model model, const glm::mat4& model_to_world, const Material& material) {
  SceneObject object;
  object.name = "object";
  model.materials.assign(1, material);
  object.materials = model.materials;
  object.model = std::make_shared<const Model>(std::move(model));
  object.model_to_world = model_to_world;
  return object;
}

RenderSettings raster_settings(int width, int height, AovSet aovs) {
  RenderSettings s;
  s.engine = EngineKind::Raster;
  s.width = width;
  s.height = height;
  s.aovs = aovs;
  return s;
}

TileBuffer render_full(const PreparedScene& scene, const RenderSettings& settings) {
  TileBuffer out;
  render_tile(scene, settings, Rect{0, 0, settings.width, settings.height}, out);
  return out;
}

}  // namespace farm::test
