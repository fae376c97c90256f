#include "renderer/scene/mesh.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <limits>
#include <map>
#include <tuple>

namespace farm {

AABB Mesh::bounds() const {
  AABB box;
  for (const glm::vec3& p : positions) box.grow(p);
  return box;
}

void generate_smooth_normals(Mesh& mesh, float crease_degrees) {
  using Key = std::tuple<float, float, float>;
  auto key = [](const glm::vec3& p) { return Key{p.x, p.y, p.z}; };
  const std::size_t n_tris = mesh.triangles.size();

  // Face normals: area-weighted (cross product, length = twice the area) and unit.
  std::vector<glm::vec3> weighted(n_tris), unit(n_tris);
  std::map<Key, std::vector<std::size_t>> faces_at;  // faces touching each position
  for (std::size_t t = 0; t < n_tris; ++t) {
    const glm::uvec3& tri = mesh.triangles[t];
    const glm::vec3 &a = mesh.positions[tri.x], &b = mesh.positions[tri.y], &c = mesh.positions[tri.z];
    weighted[t] = glm::cross(b - a, c - a);
    const float len = glm::length(weighted[t]);
    unit[t] = len > 0.0f ? weighted[t] / len : glm::vec3(0.0f);
    for (int k = 0; k < 3; ++k) {
      std::vector<std::size_t>& list = faces_at[key(mesh.positions[tri[k]])];
      if (list.empty() || list.back() != t) list.push_back(t);
    }
  }

  // Each corner averages the faces at its position within the crease angle of its own face;
  // corners that agree on position and normal share one vertex.
  const float cos_crease = std::cos(glm::radians(crease_degrees));
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::vec2> uvs;
  const bool has_uvs = mesh.uvs.size() == mesh.positions.size();
  // (position, normal, uv): corners at one position with different texture coordinates (a seam)
  // stay apart. Meshes without texture coordinates key every uv as 0.
  std::map<std::tuple<Key, float, float, float, float, float>, unsigned> vertex_of;
  // A corner's normal depends only on its position and its face's unit normal, so it is worked
  // out once for each such pair. Without this, N faces meeting at one position cost N^2 steps:
  // a 160 kB OBJ of 20000 copies of one triangle (or of zero-area faces, whose unit normals are
  // all zero) took a minute to load. The sum runs over the same faces in the same order as
  // before, so every normal keeps its bits.
  std::map<std::tuple<Key, float, float, float>, glm::vec3> normal_of;  // (position, face normal)
  for (std::size_t t = 0; t < n_tris; ++t) {
    glm::uvec3& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 p = mesh.positions[tri[k]];
      const glm::vec2 uv = has_uvs ? mesh.uvs[tri[k]] : glm::vec2(0.0f);
      const auto corner_normal = [&] {
        glm::vec3 sum(0.0f);
        for (std::size_t f : faces_at[key(p)]) {
          if (glm::dot(unit[f], unit[t]) >= cos_crease) sum += weighted[f];
        }
        const float len = glm::length(sum);
        return len > 0.0f ? sum / len : glm::vec3(0.0f, 0.0f, 1.0f);
      };
      glm::vec3 n;
      // A face whose cross product overflowed has a NaN unit normal, which cannot be a map key
      // (NaN breaks the key order): such corners are worked out each time, as before.
      if (std::isnan(unit[t].x) || std::isnan(unit[t].y) || std::isnan(unit[t].z)) {
        n = corner_normal();
      } else {
        const auto [known, fresh] =
            normal_of.try_emplace({key(p), unit[t].x, unit[t].y, unit[t].z}, glm::vec3(0.0f));
        if (fresh) known->second = corner_normal();
        n = known->second;
      }
      auto [it, inserted] = vertex_of.try_emplace({key(p), n.x, n.y, n.z, uv.x, uv.y},
                                                  static_cast<unsigned>(positions.size()));
      if (inserted) {
        positions.push_back(p);
        normals.push_back(n);
        if (has_uvs) uvs.push_back(uv);
      }
      tri[k] = it->second;
    }
  }
  mesh.positions = std::move(positions);
  mesh.normals = std::move(normals);
  mesh.uvs = std::move(uvs);
  mesh.tangents.clear();  // a file's tangents mean nothing without its normals (glTF 2.0, 3.7.2.1)
}

void generate_tangents(Mesh& mesh) {
  const std::size_t n = mesh.positions.size();
  if (mesh.uvs.size() != n || mesh.normals.size() != n) return;
  // A triangle's orientation: whether its uv map keeps (+1) or mirrors (-1) its winding; 0 where
  // its uvs are degenerate (it adds nothing). A vertex whose triangles disagree (a mirrored
  // island's seam) is split: the mirrored side gets a copy of it, so each side keeps its frame.
  std::vector<int> orientation(mesh.triangles.size(), 0);
  std::vector<int> vertex_orientation(n, 0);
  std::vector<std::uint32_t> twin(n, std::numeric_limits<std::uint32_t>::max());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    glm::uvec3& t = mesh.triangles[f];
    const glm::vec2 d1 = mesh.uvs[t.y] - mesh.uvs[t.x], d2 = mesh.uvs[t.z] - mesh.uvs[t.x];
    const float det = d1.x * d2.y - d2.x * d1.y;
    if (!(std::fabs(det) > 0.0f) || !std::isfinite(det)) continue;
    orientation[f] = det > 0.0f ? 1 : -1;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& v = t[k];
      if (vertex_orientation[v] == 0) vertex_orientation[v] = orientation[f];
      if (vertex_orientation[v] == orientation[f]) continue;
      if (twin[v] == std::numeric_limits<std::uint32_t>::max()) {
        twin[v] = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(mesh.positions[v]);
        mesh.normals.push_back(mesh.normals[v]);
        mesh.uvs.push_back(mesh.uvs[v]);
      }
      v = twin[v];
    }
  }
  const std::size_t vertices = mesh.positions.size();
  // MikkTSpace's weighting (Mikkelsen 2008): at each corner, the triangle's directions of
  // growing u and v are laid into the plane of the vertex normal and normalised, and weighted by
  // the corner's angle in that plane; so neither a triangle's size nor its uv scale tips the sum.
  std::vector<glm::vec3> along_u(vertices, glm::vec3(0.0f)), along_v(vertices, glm::vec3(0.0f));
  const auto in_plane = [](const glm::vec3& normal, const glm::vec3& d) {
    const glm::vec3 p = d - normal * glm::dot(normal, d);
    const float length = glm::length(p);
    return length > 1e-20f && std::isfinite(length) ? p / length : glm::vec3(0.0f);
  };
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    if (orientation[f] == 0) continue;
    const glm::uvec3& t = mesh.triangles[f];
    const glm::vec3 e1 = mesh.positions[t.y] - mesh.positions[t.x], e2 = mesh.positions[t.z] - mesh.positions[t.x];
    const glm::vec2 d1 = mesh.uvs[t.y] - mesh.uvs[t.x], d2 = mesh.uvs[t.z] - mesh.uvs[t.x];
    // Solving e = du * U + dv * V for U and V, up to the positive factor 1 / |det|.
    const float sign = static_cast<float>(orientation[f]);
    const glm::vec3 u = sign * (d2.y * e1 - d1.y * e2), v = sign * (d1.x * e2 - d2.x * e1);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t i = t[k];
      const glm::vec3& normal = mesh.normals[i];
      const glm::vec3 to_next = in_plane(normal, mesh.positions[t[(k + 1) % 3]] - mesh.positions[i]);
      const glm::vec3 to_prev = in_plane(normal, mesh.positions[t[(k + 2) % 3]] - mesh.positions[i]);
      const float angle = std::acos(std::clamp(glm::dot(to_next, to_prev), -1.0f, 1.0f));
      along_u[i] += angle * in_plane(normal, u);
      along_v[i] += angle * in_plane(normal, v);
    }
  }
  mesh.tangents.resize(vertices);
  for (std::size_t i = 0; i < vertices; ++i) {
    const glm::vec3& normal = mesh.normals[i];
    glm::vec3 t = along_u[i] - normal * glm::dot(normal, along_u[i]);
    float length = glm::length(t);
    if (!(length > 1e-20f) || !std::isfinite(length)) {
      // Any direction across the normal: the axis it leans on least.
      const glm::vec3 axis = std::fabs(normal.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
      t = axis - normal * glm::dot(normal, axis);
      length = glm::length(t);
    }
    t /= length;
    // The bitangent points where v falls: up the image, as glTF's normal maps (+Y green) say.
    const float w = glm::dot(glm::cross(normal, t), along_v[i]) > 0.0f ? -1.0f : 1.0f;
    mesh.tangents[i] = glm::vec4(t, w);
  }
}

}  // namespace farm
