#pragma once
// Triangle mesh in model space. Loaders bake a file's node hierarchy into the positions, so a
// model is one triangle soup per material group and the job's object transform sits on top.
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <string>
#include <vector>

#include "renderer/geometry/aabb.h"

namespace farm {

struct Mesh {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;        // one per position, unit length
  // Texture coordinates (renderer/texture/texture.h's convention: v down): one per position, or
  // none when the file has none.
  std::vector<glm::vec2> uvs;
  // Tangent frames for normal maps, glTF's TANGENT: one per position, or none. xyz the unit
  // tangent (where u grows along the surface, perpendicular to the normal), w +1 or -1: the
  // bitangent, w * cross(normal, tangent), points where v falls (up the image: a normal map's +Y).
  std::vector<glm::vec4> tangents;
  std::vector<glm::uvec3> triangles;     // indices into positions
  std::uint32_t material = 0;            // index into Model::materials
  int node = -1;  // glTF: the Model::nodes entry whose rest world transform is baked in; else -1

  std::size_t triangle_count() const { return triangles.size(); }
  AABB bounds() const;
};

// Area-weighted vertex normals for a mesh that has none. Faces meeting at a position are smoothed
// together when their normals differ by less than `crease_degrees`, so a de-indexed mesh (one
// vertex per face corner) still comes out smooth while a box keeps its hard edges. Vertices are
// split where one position needs several normals (or, with texture coordinates, several of
// those); triangles are rewritten to match.
inline constexpr float kDefaultCreaseDegrees = 60.0f;
void generate_smooth_normals(Mesh& mesh, float crease_degrees = kDefaultCreaseDegrees);

// Tangents for a mesh with normals and texture coordinates but no tangents, built as MikkTSpace
// builds them (Mikkelsen 2008; glTF asks for it): at each corner the triangle's directions of
// growing u and v, laid into the plane of the vertex normal and normalised, weighted by the
// corner's angle there, summed per vertex; w the side v's sum lies on. A vertex shared by
// triangles whose uv maps disagree in orientation (the seam of a mirrored island) is split, each
// side keeping its own frame, and triangles are rewritten to match. Written from the paper, not
// from its reference code: a vertex whose corners are not joined by edges (a bow-tie) is not
// split as MikkTSpace would. A vertex whose uvs are degenerate gets any tangent perpendicular to
// its normal.
void generate_tangents(Mesh& mesh);

}  // namespace farm
