#include "renderer/loaders/join_identical_vertices.h"

#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "renderer/util/mix64.h"

namespace farm {
namespace {

// Assimp's rule: two vertices are one when their positions hash alike and their positions,
// normals, first texture coordinates, tangents and bitangents each differ by at most 1e-5 in
// length (an attribute the mesh lacks counts as zero; colours are not compared; tangents count only
// where bitangents come with them). A vertex that matches several kept ones joins the most
// recently kept: Assimp asks a std::unordered_map, which puts each new key at the front of its
// bucket and returns the first match it meets.
//
// Positions hash alike when they are the same floats, +0 and -0 alike: so for Assimp's hash
// (std::hash of x, y and z, combined boost-style, a library call per float) and for this one,
// one mix of the three floats' bits. Only two different positions whose 64-bit hashes collided
// could be treated otherwise: for a million different positions, odds of about 3 in 10^8.
constexpr float kEpsilon = 1e-5f;
constexpr float kSquareEpsilon = kEpsilon * kEpsilon;

std::uint64_t position_hash(const aiVector3D& p) {
  const auto bits = [](float c) { return std::bit_cast<std::uint32_t>(c == 0.0f ? 0.0f : c); };
  return mix64(mix64((std::uint64_t{bits(p.x)} << 32) | bits(p.y)) ^ bits(p.z));
}

inline bool apart(const aiVector3D* values, unsigned a, unsigned b) {
  if (values == nullptr) return false;  // absent: zero on both sides
  return (values[a] - values[b]).SquareLength() > kSquareEpsilon;
}

bool same_vertex(const aiMesh& mesh, unsigned a, unsigned b) {
  // Tangents count only with their bitangents, as Assimp reads them.
  const bool frames = mesh.HasTangentsAndBitangents();
  return !apart(mesh.mVertices, a, b) && !apart(mesh.mNormals, a, b) && !apart(mesh.mTextureCoords[0], a, b) &&
         !(frames && (apart(mesh.mTangents, a, b) || apart(mesh.mBitangents, a, b)));
}

// Position hash -> the newest kept vertex of that hash, in one flat array probed linearly: what a
// std::unordered_map did here, without its allocation and free per key (a 34,000-triangle model
// has 100,000 corners to look up). With the hash above, the bunny's join went from 49.0 to 22.6
// million instructions (callgrind).
class NewestByHash {
 public:
  static constexpr unsigned kNone = ~0u;

  explicit NewestByHash(std::size_t keys) {
    std::size_t capacity = 16;
    while (capacity < 2 * keys) capacity *= 2;  // at most half full: probes stay short
    shift_ = 64 - static_cast<unsigned>(std::countr_zero(capacity));
    hashes_.resize(capacity);
    newest_.assign(capacity, kNone);
  }

  // The slot of `hash`, kNone in it the first time it is asked for.
  unsigned& operator[](std::uint64_t hash) {
    const std::size_t mask = hashes_.size() - 1;
    std::size_t i = static_cast<std::size_t>(hash >> shift_);  // the hash is mixed already: its top bits
    for (;; i = (i + 1) & mask) {
      if (newest_[i] == kNone) {
        hashes_[i] = hash;
        return newest_[i];  // a new key: the caller fills it in before the next lookup
      }
      if (hashes_[i] == hash) return newest_[i];
    }
  }

 private:
  unsigned shift_ = 0;
  std::vector<std::uint64_t> hashes_;
  std::vector<unsigned> newest_;
};

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
  constexpr unsigned kNone = NewestByHash::kNone;
  std::vector<unsigned> kept;          // for each kept vertex, the vertex it was
  std::vector<unsigned> older;         // for each kept vertex, the kept one before it of its hash
  std::vector<unsigned> joined_to(count, 0);
  NewestByHash newest(count);
  for (unsigned v = 0; v < count; ++v) {
    if (!used[v]) continue;
    unsigned& slot = newest[position_hash(mesh.mVertices[v])];
    unsigned match = kNone;
    for (unsigned k = slot; k != kNone && match == kNone; k = older[k]) {
      if (same_vertex(mesh, kept[k], v)) match = k;
    }
    if (match == kNone) {
      match = static_cast<unsigned>(kept.size());
      kept.push_back(v);
      older.push_back(slot);
      slot = match;
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
