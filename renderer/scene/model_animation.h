#pragma once
// A model file's node hierarchy and its keyframed node animations (glTF 2.0 section 3.11): the
// loaders bake each node's rest-pose world transform into its meshes, and these say how an
// animation moves the nodes from there, so that a posed frame can reuse the baked meshes (and
// their BVHs) with one matrix per mesh on top.
#include <cstddef>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace farm {

struct Mesh;
struct Model;

// One node as the file gave it. Its rest local transform is T * R * S, or `matrix` where the file
// gave one (glTF forbids animating such a node).
struct ModelNode {
  std::string name;
  int parent = -1;  // index into Model::nodes; -1 for a root
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // w, x, y, z; unit length
  glm::vec3 scale{1.0f};
  std::optional<glm::mat4> matrix;
};

enum class AnimationPath { Translation, Rotation, Scale };
enum class SamplerInterpolation { Step, Linear, CubicSpline };

// Keyframes of one node property. `times` are seconds, strictly increasing, at least one. Values
// are vec3 for translation and scale and unit quaternions for rotation; CubicSpline keeps three
// per key (in-tangent, value, out-tangent, in that order), the others one.
struct AnimationSampler {
  SamplerInterpolation interpolation = SamplerInterpolation::Linear;
  std::vector<float> times;
  std::vector<glm::vec3> vec3_values;  // translation, scale
  std::vector<glm::quat> quat_values;  // rotation
};

struct AnimationChannel {
  int node = -1;  // index into Model::nodes
  AnimationPath path = AnimationPath::Translation;
  AnimationSampler sampler;
};

struct ModelAnimation {
  std::string name;
  std::vector<AnimationChannel> channels;

  // The last key time of any channel (0 for none): where every channel holds its last value.
  double end_seconds() const;
};

// What is wrong with a sampler for `path` (key and value counts, order of the times, finite
// values), or empty when nothing is. The sample functions below require a sampler without one.
std::string sampler_problem(const AnimationSampler& sampler, AnimationPath path);

// A sampler's value at `time_seconds`: before the first key and after the last it holds the end
// values; Step holds each key's value until the next key; Linear interpolates (rotations by
// shortest-path slerp); CubicSpline is the Hermite spline of glTF 2.0 appendix C, its tangents
// scaled by the key interval. Rotations come back unit length. Throws std::invalid_argument for a
// sampler without keys or whose value count does not fit them (the faults that would read out of
// bounds); other problems sampler_problem names give answers, just not meaningful ones.
glm::vec3 sample_vec3(const AnimationSampler& sampler, double time_seconds);
glm::quat sample_rotation(const AnimationSampler& sampler, double time_seconds);

// A node's rest local transform: `matrix`, or T * R * S.
glm::mat4 rest_local_matrix(const ModelNode& node);

// Every node's world (model-space) matrix, parent world * local, with `animation` at
// `time_seconds` replacing the rest translation, rotation and scale it animates; nullptr gives the
// rest pose, the transforms the loaders baked into the meshes. Nodes may come in any order.
// Throws InputError for a hierarchy with a cycle or a parent out of range, and for a channel that
// names a missing node or one with a matrix (the loaders refuse such files).
std::vector<glm::mat4> node_world_matrices(const Model& model, const ModelAnimation* animation,
                                           double time_seconds);

// The index of the first animation called `name`.
std::optional<std::size_t> find_animation(const Model& model, std::string_view name);

// Whether a rest world matrix can be undone without losing the baked positions: finite, and its
// linear part far from singular (|det| against the product of its column lengths). A loader
// refuses a file with an animated node whose meshes were baked with a matrix that is not.
bool invertible_for_posing(const glm::mat4& rest_world);

// Per node, the matrix that takes positions baked with the node's rest world matrix to where
// `animation` at `time_seconds` puts them: posed_world * inverse(rest_world). Exactly the identity
// for a node the animation does not move (nullptr: every node). This is what the scene builder
// puts between a mesh's positions and its object transform (object_transform * this), so that
// the mesh's BVH is built once and only the top level changes per frame. A moved node whose rest
// matrix is not invertible_for_posing has no such matrix: its entry is all NaN (a loaded model's
// meshes never have such a node; a mesh-less one may). Throws as node_world_matrices does.
std::vector<glm::mat4> rest_to_posed_matrices(const Model& model, const ModelAnimation* animation,
                                              double time_seconds);
// The same matrix for one mesh, from rest_to_posed_matrices' result: the identity for a mesh of no
// node (Mesh::node == -1); std::out_of_range for a node the result has no matrix for, and
// InputError for a node whose entry is NaN (a singular rest transform).
glm::mat4 mesh_rest_to_posed(const Mesh& mesh, const std::vector<glm::mat4>& rest_to_posed);

}  // namespace farm
