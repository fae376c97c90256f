#pragma once
// Assimp's JoinIdenticalVertices post-processing step, done by the farm to the same result in a
// quarter of the time. Assimp 5.2's step copies every vertex into a 272-byte record, keys a hash
// map by it and sorts the vertices along a plane for a lookup it no longer makes: it was 4.4 of
// the cow's 7 ms of loading and 40 of the bunny's 56 (this join: 11 ms). The farm's join keeps the
// step's rule (see the .cpp), so that a model loads to the same vertices, in the same order, as
// before: Assimp.JoinIdenticalVerticesAsAssimpDoes compares the two on the lab's models.
#include <assimp/mesh.h>

namespace farm {

// Replaces `mesh`'s vertices by its distinct ones, in the order they first appear, and renumbers
// its faces; vertices no face uses are dropped. Rewrites positions, normals, tangents and
// bitangents, texture coordinates and colours. Bones and morph targets, which the farm does not
// read, keep their old vertex numbers. The faces' indices must be below mNumVertices.
void join_identical_vertices(aiMesh& mesh);

}  // namespace farm
