#include "renderer/loaders/join_identical_vertices.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

namespace farm {
namespace {

// Assimp's rule: two vertices are one when their positions hash alike (std::hash of x, y and z
// combined, boost-style: equal floats, +0 and -0 alike) and their positions, normals, first
// texture coordinates, tangents and bitangents each differ by at most 1e-5 in length (an
// attribute the mesh lacks counts as zero; colours are not compared; tangents count only where
// bitangents come with them). A vertex that matches several kept ones joins the most recently
// kept: Assimp asks a std::unordered_map, which puts each new key at the front of its bucket and
// returns the first match it meets.
constexpr float kEpsilon = 1e-5f;
constexpr float kSquareEpsilon = kEpsilon * kEpsilon;

std::size_t position_hash(const aiVector3D& p) {
  std::size_t seed = 0;
  for (const float c : {p.x, p.y, p.z}) seed ^= std::hash<float>{}(c) + 0x9e3779b9 + (seed << 6) + (seed >> 2);
  return seed;
}

bool apart(const aiVector3D* values, unsigned a, unsigned b) {
  if (values == nullptr) return false;  // absent: zero on both sides
  return (values[a] - values[b]).SquareLength() > kSquareEpsilon;
}

bool same_vertex(const aiMesh& mesh, unsigned a, unsigned b) {
  // Tangents count only with their bitangents, as Assimp reads them.
  const bool frames = mesh.HasTangentsAndBitangents();
  return !apart(mesh.mVertices, a, b) && !apart(mesh.mNormals, a, b) && !apart(mesh.mTextureCoords[0], a, b) &&
         !(frames && (apart(mesh.mTangents, a, b) || apart(mesh.mBitangents, a, b)));
}

// `values` (owned by the mesh, as Assimp allocates it) replaced by the kept vertices' values.
template <typename T>
void keep_only(T*& values, const std::vector<unsigned>& kept) {
  if (values == nullptr) return;
  T* joined = new T[kept.size()];
  for (std::size_t i = 0; i < kept.size(); ++i) joined[i] = values[kept[i]];
  delete[] values;
  values = joined;
}

}  // namespace

void join_identical_vertices(aiMesh& mesh) {
  if (!mesh.HasPositions() || !mesh.HasFaces()) return;
  const unsigned count = mesh.mNumVertices;
  std::vector<bool> used(count, false);
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    for (unsigned i = 0; i < face.mNumIndices; ++i) used[face.mIndices[i]] = true;
  }
  constexpr unsigned kNone = ~0u;
  std::vector<unsigned> kept;          // for each kept vertex, the vertex it was
  std::vector<unsigned> older;         // for each kept vertex, the kept one before it of its hash
  std::vector<unsigned> joined_to(count, 0);
  std::unordered_map<std::size_t, unsigned> newest;  // position hash -> the newest kept vertex of it
  newest.reserve(count);
  for (unsigned v = 0; v < count; ++v) {
    if (!used[v]) continue;
    const auto slot = newest.try_emplace(position_hash(mesh.mVertices[v]), kNone).first;
    unsigned match = kNone;
    for (unsigned k = slot->second; k != kNone && match == kNone; k = older[k]) {
      if (same_vertex(mesh, kept[k], v)) match = k;
    }
    if (match == kNone) {
      match = static_cast<unsigned>(kept.size());
      kept.push_back(v);
      older.push_back(slot->second);
      slot->second = match;
    }
    joined_to[v] = match;
  }

  keep_only(mesh.mVertices, kept);
  keep_only(mesh.mNormals, kept);
  keep_only(mesh.mTangents, kept);
  keep_only(mesh.mBitangents, kept);
  for (unsigned c = 0; mesh.HasVertexColors(c); ++c) keep_only(mesh.mColors[c], kept);
  for (unsigned t = 0; mesh.HasTextureCoords(t); ++t) keep_only(mesh.mTextureCoords[t], kept);
  mesh.mNumVertices = static_cast<unsigned>(kept.size());
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    aiFace& face = mesh.mFaces[f];
    for (unsigned i = 0; i < face.mNumIndices; ++i) face.mIndices[i] = joined_to[face.mIndices[i]];
  }
}

}  // namespace farm
