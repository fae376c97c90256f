// glTF node animations: the loader's node hierarchy and animation channels, and their evaluation
// (renderer/scene/model_animation.h), over tests/data/animated_nodes.gltf, whose layout and
// hand-computed answers are in tests/data/make_gltf_assets.py.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/trigonometric.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "renderer/scene/model.h"
#include "renderer/scene/model_animation.h"
#include "renderer/util/input_error.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::TempDir;

const fs::path kData = FARM_TEST_DATA;
const fs::path kAnimated = kData / "animated_nodes.gltf";

// Node indices of animated_nodes.gltf.
constexpr int kArm = 0, kBase = 1, kHead = 2, kHat = 3, kFixed = 4;
const std::vector<glm::vec3> kTriangle = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
const float kS45 = std::sqrt(0.5f);

std::string read_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

const Model& animated_model() {
  static const Model model = load_model(kAnimated);
  return model;
}

const ModelAnimation& animation(const char* name) {
  const Model& m = animated_model();
  const auto index = find_animation(m, name);
  EXPECT_TRUE(index.has_value()) << name;
  return m.animations.at(index.value_or(0));
}

glm::mat4 world_at(const char* name, double t, int node) {
  return node_world_matrices(animated_model(), &animation(name), t).at(node);
}

// ---- Hand-written matrices (column-major, as GLM and glTF keep them) ----------------------------

glm::mat4 translate(float x, float y, float z) {
  glm::mat4 m(1.0f);
  m[3] = glm::vec4(x, y, z, 1.0f);
  return m;
}

glm::mat4 scale(float s) {
  glm::mat4 m(s);
  m[3][3] = 1.0f;
  return m;
}

glm::mat4 rotate_y(float degrees) {
  const float c = std::cos(glm::radians(degrees));
  const float s = std::sin(glm::radians(degrees));
  glm::mat4 m(1.0f);
  m[0] = glm::vec4(c, 0.0f, -s, 0.0f);  // +X turns towards -Z
  m[2] = glm::vec4(s, 0.0f, c, 0.0f);   // +Z turns towards +X
  return m;
}

void expect_matrix_near(const glm::mat4& actual, const glm::mat4& expected, float tol = 1e-5f) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      EXPECT_NEAR(actual[c][r], expected[c][r], tol) << "column " << c << " row " << r;
    }
  }
}

void expect_vec3_near(const glm::vec3& actual, const glm::vec3& expected, float tol = 1e-5f) {
  EXPECT_NEAR(actual.x, expected.x, tol);
  EXPECT_NEAR(actual.y, expected.y, tol);
  EXPECT_NEAR(actual.z, expected.z, tol);
}

glm::vec3 apply(const glm::mat4& m, const glm::vec3& p) {
  return glm::vec3(m * glm::vec4(p, 1.0f));
}

const Mesh* mesh_named(const Model& m, const std::string& name) {
  for (const Mesh& mesh : m.meshes)
    if (mesh.name == name) return &mesh;
  return nullptr;
}

// ---- Loading ------------------------------------------------------------------------------------

TEST(GltfAnimation, LoadsEveryNodeWithItsParentAndRestTransform) {
  const Model& m = animated_model();
  ASSERT_EQ(m.nodes.size(), 5u);
  EXPECT_EQ(m.nodes[kArm].name, "arm");
  EXPECT_EQ(m.nodes[kArm].parent, kBase);  // the parent comes after its child in the file
  EXPECT_EQ(m.nodes[kBase].parent, -1);
  EXPECT_EQ(m.nodes[kHead].parent, kBase);
  EXPECT_EQ(m.nodes[kHat].parent, kHead);
  EXPECT_EQ(m.nodes[kFixed].parent, -1);
  expect_vec3_near(m.nodes[kArm].translation, {0, 2, 0});
  expect_vec3_near(m.nodes[kBase].scale, {1, 1, 1});
  EXPECT_FALSE(m.nodes[kBase].matrix.has_value());
  ASSERT_TRUE(m.nodes[kFixed].matrix.has_value());
  expect_matrix_near(*m.nodes[kFixed].matrix, translate(0, 0, -3));
}

TEST(GltfAnimation, EachMeshNamesTheNodeItWasBakedWith) {
  const Model& m = animated_model();
  const std::pair<const char*, int> expected[] = {
      {"arm", kArm}, {"head", kHead}, {"hat", kHat}, {"fixed", kFixed}};
  for (const auto& [name, node] : expected) {
    const Mesh* mesh = mesh_named(m, name);
    ASSERT_NE(mesh, nullptr) << name;
    EXPECT_EQ(mesh->node, node) << name;
  }
}

TEST(GltfAnimation, LoadsThreeNamedAnimationsWithTheirChannels) {
  const Model& m = animated_model();
  ASSERT_EQ(m.animations.size(), 3u);
  EXPECT_EQ(find_animation(m, "walk"), 0u);
  EXPECT_EQ(find_animation(m, "hop"), 1u);
  EXPECT_EQ(find_animation(m, "spline"), 2u);
  EXPECT_FALSE(find_animation(m, "run").has_value());

  const ModelAnimation& walk = m.animations[0];
  ASSERT_EQ(walk.channels.size(), 2u);
  EXPECT_EQ(walk.channels[0].node, kArm);
  EXPECT_EQ(walk.channels[0].path, AnimationPath::Translation);
  EXPECT_EQ(walk.channels[0].sampler.interpolation, SamplerInterpolation::Linear);
  EXPECT_EQ(walk.channels[0].sampler.times, (std::vector<float>{0.0f, 2.0f}));
  EXPECT_EQ(walk.channels[1].node, kHead);
  EXPECT_EQ(walk.channels[1].path, AnimationPath::Rotation);
  ASSERT_EQ(walk.channels[1].sampler.quat_values.size(), 2u);
  EXPECT_DOUBLE_EQ(walk.end_seconds(), 2.0);

  const ModelAnimation& hop = m.animations[1];
  ASSERT_EQ(hop.channels.size(), 1u);
  EXPECT_EQ(hop.channels[0].path, AnimationPath::Scale);
  EXPECT_EQ(hop.channels[0].sampler.interpolation, SamplerInterpolation::Step);

  const ModelAnimation& spline = m.animations[2];
  ASSERT_EQ(spline.channels.size(), 1u);
  EXPECT_EQ(spline.channels[0].sampler.interpolation, SamplerInterpolation::CubicSpline);
  EXPECT_EQ(spline.channels[0].sampler.vec3_values.size(), 6u);  // in, value, out per key
}

// ---- The rest pose ------------------------------------------------------------------------------

TEST(GltfAnimation, RestPoseIsTheTransformBakedIntoEveryMesh) {
  const Model& m = animated_model();
  const std::vector<glm::mat4> rest = node_world_matrices(m, nullptr, 0.0);
  ASSERT_EQ(rest.size(), m.nodes.size());
  expect_matrix_near(rest[kArm], translate(1, 2, 0));
  expect_matrix_near(rest[kHead], translate(1, 0, 0));
  expect_matrix_near(rest[kHat], translate(1, 0, 1));
  expect_matrix_near(rest[kFixed], translate(0, 0, -3));
  for (const Mesh& mesh : m.meshes) {
    SCOPED_TRACE(mesh.name);
    ASSERT_EQ(mesh.positions.size(), kTriangle.size());
    for (std::size_t i = 0; i < kTriangle.size(); ++i) {
      // Bit for bit: the loader bakes with these very matrices.
      EXPECT_EQ(mesh.positions[i], apply(rest[mesh.node], kTriangle[i]));
    }
  }
}

TEST(GltfAnimation, QuadSceneRestPoseGivesTheBakedPositionsOfBefore) {
  for (const char* name : {"quad_scene.gltf", "quad_scene.glb"}) {
    SCOPED_TRACE(name);
    const Model m = load_model(kData / name);
    EXPECT_TRUE(m.animations.empty());
    ASSERT_EQ(m.nodes.size(), 6u);
    EXPECT_EQ(m.nodes[1].parent, 0);
    const Mesh* quad = mesh_named(m, "quad");
    const Mesh* strip = mesh_named(m, "strip");
    ASSERT_NE(quad, nullptr);
    ASSERT_NE(strip, nullptr);
    EXPECT_EQ(quad->node, 1);
    EXPECT_EQ(strip->node, 2);
    const std::vector<glm::mat4> rest = node_world_matrices(m, nullptr, 0.0);
    // The corners LoaderGltf.NodeTransformsAreBakedIntoPositionsAndNormals checks.
    expect_vec3_near(apply(rest[1], {1, 0, 0}), {1, 3, 1});
    expect_vec3_near(apply(rest[1], {1, 1, 0}), {1, 5, 1});
    expect_vec3_near(apply(rest[2], {1, 1, 0}), {1, 1, -5});
  }
}

// ---- LINEAR -------------------------------------------------------------------------------------

TEST(GltfAnimation, LinearTranslationHoldsBeforeInterpolatesBetweenAndHoldsAfter) {
  // arm: (0,2,0) at 0 s to (4,2,0) at 2 s, under base's (1,0,0).
  expect_matrix_near(world_at("walk", -1.0, kArm), translate(1, 2, 0));  // before the first key
  expect_matrix_near(world_at("walk", 0.0, kArm), translate(1, 2, 0));   // on the first key
  expect_matrix_near(world_at("walk", 0.5, kArm), translate(2, 2, 0));
  expect_matrix_near(world_at("walk", 1.0, kArm), translate(3, 2, 0));
  expect_matrix_near(world_at("walk", 2.0, kArm), translate(5, 2, 0));   // on the last key
  expect_matrix_near(world_at("walk", 30.0, kArm), translate(5, 2, 0));  // after it: held
}

TEST(GltfAnimation, LinearRotationSlerpsHalfwayTo45Degrees) {
  expect_matrix_near(world_at("walk", 1.0, kHead), translate(1, 0, 0) * rotate_y(45.0f));
  // The hat, (0,0,1) under the head, swings with it.
  expect_matrix_near(world_at("walk", 1.0, kHat),
                     translate(1.0f + kS45, 0.0f, kS45) * rotate_y(45.0f));
}

TEST(GltfAnimation, LinearRotationSlerpsAQuarterOfTheWayTo22Point5Degrees) {
  // Here a normalised lerp of the quaternions would give 21.6 degrees: only slerp keeps the
  // angle proportional to time.
  expect_matrix_near(world_at("walk", 0.5, kHead), translate(1, 0, 0) * rotate_y(22.5f));
  expect_matrix_near(world_at("walk", 1.5, kHead), translate(1, 0, 0) * rotate_y(67.5f));
}

TEST(GltfAnimation, LinearRotationHoldsItsEndsAndMeetsItsKeys) {
  expect_matrix_near(world_at("walk", -5.0, kHead), translate(1, 0, 0));
  expect_matrix_near(world_at("walk", 0.0, kHead), translate(1, 0, 0));
  expect_matrix_near(world_at("walk", 2.0, kHead), translate(1, 0, 0) * rotate_y(90.0f));
  expect_matrix_near(world_at("walk", 9.0, kHead), translate(1, 0, 0) * rotate_y(90.0f));
  expect_matrix_near(world_at("walk", 9.0, kHat), translate(2, 0, 0) * rotate_y(90.0f));
}

TEST(GltfAnimation, LinearRotationTakesTheShorterArcWhenAKeyHasTheOppositeSign) {
  // -q is the same rotation as q. Towards the second key as written, halfway is 135 degrees about
  // -Y (the long way round); flipped onto the near side, it is 45 degrees about +Y.
  AnimationSampler s;
  s.interpolation = SamplerInterpolation::Linear;
  s.times = {0.0f, 1.0f};
  s.quat_values = {glm::quat(1, 0, 0, 0), glm::quat(-kS45, 0, -kS45, 0)};
  const glm::quat q = sample_rotation(s, 0.5);
  EXPECT_NEAR(glm::length(q), 1.0f, 1e-6f);
  expect_matrix_near(glm::mat4_cast(q), rotate_y(45.0f));
}

// ---- STEP ---------------------------------------------------------------------------------------

TEST(GltfAnimation, StepScaleHoldsEachKeyUntilTheNext) {
  // base: scale 1 at 0 s, 2 at 1 s, 0.5 at 2 s; translation (1,0,0).
  const std::pair<double, float> expected[] = {{-1.0, 1.0f}, {0.0, 1.0f}, {0.5, 1.0f},
                                               {0.999, 1.0f}, {1.0, 2.0f}, {1.5, 2.0f},
                                               {1.999, 2.0f}, {2.0, 0.5f}, {100.0, 0.5f}};
  for (const auto& [t, s] : expected) {
    SCOPED_TRACE(testing::Message() << "t = " << t);
    expect_matrix_near(world_at("hop", t, kBase), translate(1, 0, 0) * scale(s));
  }
}

TEST(GltfAnimation, ChildrenOfAnAnimatedParentMoveWithIt) {
  // hop at 1 s scales base by 2: arm's (0,2,0) becomes (0,4,0), hat's (0,0,1) becomes (0,0,2).
  expect_matrix_near(world_at("hop", 1.0, kArm), translate(1, 4, 0) * scale(2.0f));
  expect_matrix_near(world_at("hop", 1.0, kHat), translate(1, 0, 2) * scale(2.0f));
  // A node outside the animated tree stays where it was.
  expect_matrix_near(world_at("hop", 1.0, kFixed), translate(0, 0, -3));
}

// ---- CUBICSPLINE --------------------------------------------------------------------------------

TEST(GltfAnimation, CubicSplineTranslationFollowsTheHermiteCurveNotTheChord) {
  // hat under base (1,0,0) and the unrotated head; the values in make_gltf_assets.py.
  expect_matrix_near(world_at("spline", 1.0, kHat), translate(2.75f, -0.25f, 1.0f));
  // A quarter of the way: basis 27/32, 9/64, 5/32, -3/64 with td = 2 on the tangents:
  // x = 2 * 3 * 9/64 + 2 * 5/32 = 1.15625, y = -2 * 3/64 = -0.09375, z = 27/32 + 5/32 = 1.
  expect_matrix_near(world_at("spline", 0.5, kHat), translate(2.15625f, -0.09375f, 1.0f));
}

TEST(GltfAnimation, CubicSplineHoldsTheKeyValuesNotTheTangentsAtTheEnds) {
  expect_matrix_near(world_at("spline", -1.0, kHat), translate(1, 0, 1));
  expect_matrix_near(world_at("spline", 0.0, kHat), translate(1, 0, 1));
  expect_matrix_near(world_at("spline", 2.0, kHat), translate(3, 0, 1));
  expect_matrix_near(world_at("spline", 4.0, kHat), translate(3, 0, 1));
}

TEST(GltfAnimation, CubicSplineRotationIsNormalised) {
  // Zero tangents halfway: the spline is the mean of the two keys, which is no unit quaternion.
  AnimationSampler s;
  s.interpolation = SamplerInterpolation::CubicSpline;
  s.times = {0.0f, 2.0f};
  const glm::quat zero(0, 0, 0, 0);
  s.quat_values = {zero, glm::quat(1, 0, 0, 0), zero, zero, glm::quat(kS45, 0, kS45, 0), zero};
  const glm::quat q = sample_rotation(s, 1.0);
  EXPECT_NEAR(glm::length(q), 1.0f, 1e-6f);
  expect_matrix_near(glm::mat4_cast(q), rotate_y(45.0f));
}

// ---- Posing the baked meshes --------------------------------------------------------------------

TEST(GltfAnimation, RestToPosedTakesBakedPositionsToThePose) {
  const Model& m = animated_model();
  for (const char* name : {"walk", "hop", "spline"}) {
    for (const double t : {0.25, 1.0, 1.75}) {
      SCOPED_TRACE(testing::Message() << name << " at " << t);
      const ModelAnimation& a = animation(name);
      const std::vector<glm::mat4> posed = node_world_matrices(m, &a, t);
      const std::vector<glm::mat4> to_posed = rest_to_posed_matrices(m, &a, t);
      for (const Mesh& mesh : m.meshes) {
        const glm::mat4 move = mesh_rest_to_posed(mesh, to_posed);
        for (std::size_t i = 0; i < kTriangle.size(); ++i) {
          expect_vec3_near(apply(move, mesh.positions[i]), apply(posed[mesh.node], kTriangle[i]));
        }
      }
    }
  }
}

TEST(GltfAnimation, RestToPosedIsExactlyTheIdentityForNodesTheAnimationLeavesAlone) {
  const Model& m = animated_model();
  const std::vector<glm::mat4> walk = rest_to_posed_matrices(m, &animation("walk"), 1.0);
  EXPECT_EQ(walk.at(kFixed), glm::mat4(1.0f));
  EXPECT_EQ(walk.at(kBase), glm::mat4(1.0f));
  EXPECT_NE(walk.at(kArm), glm::mat4(1.0f));
  for (const glm::mat4& r : rest_to_posed_matrices(m, nullptr, 1.0)) EXPECT_EQ(r, glm::mat4(1.0f));
  Mesh unplaced;  // from a loader without nodes
  EXPECT_EQ(mesh_rest_to_posed(unplaced, walk), glm::mat4(1.0f));
}

TEST(GltfAnimation, AMeshlessNodeHiddenByAZeroRestScaleMayBeAnimated) {
  // A group scaled to nothing at rest and grown by an animation: no mesh is baked with its
  // singular matrix, so the file loads; only a mesh that asked for its matrix would be an error.
  TempDir dir;
  json j = json::parse(read_file(kAnimated));
  j["nodes"].push_back({{"name", "hidden"}, {"scale", {0, 0, 0}}});
  j["scenes"][0]["nodes"].push_back(5);
  j["animations"][1]["channels"].push_back(
      {{"sampler", 0}, {"target", {{"node", 5}, {"path", "scale"}}}});
  const Model m = load_model(dir.write("hidden.gltf", j.dump()));
  const std::vector<glm::mat4> to_posed = rest_to_posed_matrices(m, &m.animations.at(1), 1.0);
  for (const Mesh& mesh : m.meshes) EXPECT_NO_THROW(mesh_rest_to_posed(mesh, to_posed));
  expect_matrix_near(node_world_matrices(m, &m.animations.at(1), 1.0).at(5), scale(2.0f));
  Mesh under_hidden;
  under_hidden.name = "under";
  under_hidden.node = 5;
  EXPECT_THROW(mesh_rest_to_posed(under_hidden, to_posed), InputError);
}

// ---- Models built by hand -----------------------------------------------------------------------

TEST(GltfAnimation, WorldMatricesComposeParentsListedAfterTheirChildren) {
  Model m;
  m.nodes.resize(3);
  m.nodes[0].parent = 1;  // grandchild first, root last
  m.nodes[0].translation = {0, 0, 1};
  m.nodes[1].parent = 2;
  m.nodes[1].rotation = glm::quat(kS45, 0, kS45, 0);  // 90 degrees about +Y
  m.nodes[2].translation = {5, 0, 0};
  const std::vector<glm::mat4> world = node_world_matrices(m, nullptr, 0.0);
  expect_matrix_near(world[2], translate(5, 0, 0));
  expect_matrix_near(world[1], translate(5, 0, 0) * rotate_y(90.0f));
  expect_matrix_near(world[0], translate(6, 0, 0) * rotate_y(90.0f));
}

TEST(GltfAnimation, CyclesAndMatrixTargetsAreInputErrors) {
  Model cycle;
  cycle.nodes.resize(3);
  cycle.nodes[0].parent = 2;
  cycle.nodes[1].parent = 0;
  cycle.nodes[2].parent = 1;
  EXPECT_THROW(node_world_matrices(cycle, nullptr, 0.0), InputError);

  Model matrix;
  matrix.nodes.resize(1);
  matrix.nodes[0].matrix = glm::mat4(1.0f);
  ModelAnimation a;
  a.name = "bad";
  a.channels.push_back({0, AnimationPath::Translation,
                        {SamplerInterpolation::Linear, {0.0f}, {glm::vec3(1.0f)}, {}}});
  try {
    node_world_matrices(matrix, &a, 0.0);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("animation 'bad' channel 0"), std::string::npos)
        << e.what();
  }
}

TEST(GltfAnimation, SamplerProblemNamesWhatIsWrong) {
  AnimationSampler s;
  EXPECT_EQ(sampler_problem(s, AnimationPath::Scale), "sampler has no keys");
  s.times = {0.0f, 1.0f, 2.0f};
  s.vec3_values.resize(5, glm::vec3(1.0f));
  EXPECT_EQ(sampler_problem(s, AnimationPath::Scale), "sampler output has 5 values for 3 keys");
  EXPECT_THROW(sample_vec3(s, 0.5), std::invalid_argument);
  s.vec3_values.resize(3, glm::vec3(1.0f));
  EXPECT_EQ(sampler_problem(s, AnimationPath::Scale), "");
  s.times = {0.0f, 2.0f, 1.0f};
  EXPECT_NE(sampler_problem(s, AnimationPath::Scale).find("not strictly increasing"),
            std::string::npos);
  s.times = {0.0f, 1.0f, 1.0f};  // equal times are no increase either
  EXPECT_NE(sampler_problem(s, AnimationPath::Scale).find("not strictly increasing"),
            std::string::npos);
}

// ---- Malformed files ----------------------------------------------------------------------------

std::string input_error_of(const fs::path& file) {
  try {
    load_model(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(loaded without an InputError)";
}

// Every case is animated_nodes.gltf with one thing broken; the message must name the file and,
// where the fault is in an animation, the animation and the channel.
TEST(GltfAnimation, MalformedAnimationsAreInputErrorsNamingAnimationAndChannel) {
  TempDir dir;
  const json good = json::parse(read_file(kAnimated));
  auto sampler = [](json& j, int a, int s) -> json& { return j["animations"][a]["samplers"][s]; };
  auto target = [](json& j, int a, int c) -> json& {
    return j["animations"][a]["channels"][c]["target"];
  };
  const std::tuple<const char*, std::function<void(json&)>, const char*> cases[] = {
      {"too_few_values", [](json& j) { j["accessors"][3]["count"] = 1; },
       "animation 0 'walk' channel 0: sampler output has 1 values for 2 keys"},
      {"cubic_not_three_per_key", [](json& j) { j["accessors"][6]["count"] = 5; },
       "animation 2 'spline' channel 0: sampler output has 5 values for 2 keys"},
      {"step_more_values_than_keys", [](json& j) { j["accessors"][2]["count"] = 2; },
       "animation 1 'hop' channel 0: sampler output has 3 values for 2 keys"},
      {"decreasing_times",
       [&](json& j) {
         // Floats 2, 0 of walk's translations (bufferView 3) read as key times.
         j["accessors"].push_back(
             {{"bufferView", 3}, {"byteOffset", 4}, {"componentType", 5126}, {"count", 2},
              {"type", "SCALAR"}});
         sampler(j, 0, 1)["input"] = 7;
       },
       "animation 0 'walk' channel 1: sampler key times are not strictly increasing"},
      {"no_keys", [](json& j) { j["accessors"][2]["count"] = 0; },
       "animation 1 'hop' channel 0: sampler has no keys"},
      {"missing_node", [&](json& j) { target(j, 1, 0)["node"] = 42; },
       "animation 1 'hop' channel 0: targets missing node 42"},
      {"matrix_node", [&](json& j) { target(j, 0, 1)["node"] = kFixed; },
       "animation 0 'walk' channel 1: targets node 4 'fixed', which has a matrix"},
      {"negative_node", [&](json& j) { target(j, 0, 0)["node"] = -3; },
       "animation 0 'walk' channel 0: targets missing node -3"},
      {"unknown_path", [&](json& j) { target(j, 0, 0)["path"] = "colour"; },
       "animation 0 'walk' channel 0: unknown target path 'colour'"},
      {"unknown_interpolation", [&](json& j) { sampler(j, 0, 0)["interpolation"] = "BEZIER"; },
       "animation 0 'walk' channel 0: unknown interpolation 'BEZIER'"},
      {"missing_sampler", [](json& j) { j["animations"][2]["channels"][0]["sampler"] = 3; },
       "animation 2 'spline' channel 0: no such sampler 3"},
      {"missing_input", [&](json& j) { sampler(j, 1, 0)["input"] = 99; },
       "animation 1 'hop' channel 0 sampler input (accessor 99): no such accessor"},
      {"missing_output", [&](json& j) { sampler(j, 0, 0)["output"] = 99; },
       "animation 0 'walk' channel 0 sampler output (accessor 99): no such accessor"},
      {"times_not_float", [](json& j) { j["accessors"][2]["componentType"] = 5123; },
       "animation 1 'hop' channel 0 sampler input: key times must be float scalars"},
      {"times_not_scalar", [](json& j) { j["accessors"][1]["type"] = "VEC2"; },
       "animation 0 'walk' channel 0 sampler input (accessor 1): unexpected element type"},
      {"rotation_not_vec4", [](json& j) { j["accessors"][4]["type"] = "VEC3"; },
       "animation 0 'walk' channel 1 sampler output (accessor 4): unexpected element type"},
      {"translation_not_vec3", [](json& j) { j["accessors"][3]["type"] = "VEC4"; },
       "animation 0 'walk' channel 0 sampler output (accessor 3): unexpected element type"},
      {"rotation_integer_not_normalized",
       [](json& j) { j["accessors"][4]["componentType"] = 5122; },
       "animation 0 'walk' channel 1 sampler output: rotations must be float or normalized"},
      {"output_past_view", [](json& j) { j["accessors"][6]["count"] = 100; },
       "animation 2 'spline' channel 0 sampler output (accessor 6): 100 elements do not fit"},
      {"duplicate_target",
       [](json& j) {
         j["animations"][0]["channels"].push_back(
             {{"sampler", 0}, {"target", {{"node", kArm}, {"path", "translation"}}}});
       },
       "animation 0 'walk' channel 2: node 0's translation is animated by an earlier channel"},
      {"singular_rest_under_animation", [](json& j) { j["nodes"][kHat]["scale"] = {1, 0, 1}; },
       "node 3 'hat' is animated, or under an animated node, but its rest transform is singular"},
  };
  for (const auto& [name, mutate, expected] : cases) {
    SCOPED_TRACE(name);
    json broken = good;
    mutate(broken);
    const fs::path file = dir.write("model/" + std::string(name) + ".gltf", broken.dump());
    const std::string message = input_error_of(file);
    EXPECT_NE(message.find(file.filename().string()), std::string::npos) << message;
    EXPECT_NE(message.find(expected), std::string::npos) << message;
  }
}

TEST(GltfAnimation, WeightsChannelsAndChannelsWithoutANodeAreSkipped) {
  TempDir dir;
  json j = json::parse(read_file(kAnimated));
  j["animations"][0]["channels"].push_back(
      {{"sampler", 0}, {"target", {{"node", kArm}, {"path", "weights"}}}});
  j["animations"][0]["channels"].push_back({{"sampler", 0}, {"target", {{"path", "rotation"}}}});
  j["animations"][0]["channels"].push_back({{"sampler", 0}});
  const Model m = load_model(dir.write("weights.gltf", j.dump()));
  ASSERT_EQ(m.animations.size(), 3u);
  EXPECT_EQ(m.animations[0].channels.size(), 2u);
}

TEST(GltfAnimation, NormalizedShortRotationsAreAccepted) {
  TempDir dir;
  json j = json::parse(read_file(kAnimated));
  // walk's rotation keys as normalized int16: (0,0,0,1) and (0,s,0,s), s = 23170 / 32767.
  const std::int16_t keys[8] = {0, 0, 0, 32767, 0, 23170, 0, 23170};
  dir.write("rotations.bin", std::string(reinterpret_cast<const char*>(keys), sizeof keys));
  j["buffers"].push_back({{"byteLength", 16}, {"uri", "rotations.bin"}});
  j["bufferViews"].push_back({{"buffer", 1}, {"byteLength", 16}});
  j["accessors"].push_back({{"bufferView", 7}, {"componentType", 5122}, {"normalized", true},
                            {"count", 2}, {"type", "VEC4"}});
  j["animations"][0]["samplers"][1]["output"] = 7;
  const Model m = load_model(dir.write("shorts.gltf", j.dump()));
  const std::vector<glm::mat4> world = node_world_matrices(m, &m.animations.at(0), 1.0);
  expect_matrix_near(world.at(kHead), translate(1, 0, 0) * rotate_y(45.0f), 1e-4f);
}

TEST(GltfAnimation, MoreThanAMillionKeysAreRefusedBeforeTheyAreRead) {
  TempDir dir;
  json j = json::parse(read_file(kAnimated));
  const std::size_t keys = 1'000'001;
  dir.write("keys.bin", std::string(keys * 4, '\0'));  // zeros: never read as times
  j["buffers"].push_back({{"byteLength", keys * 4}, {"uri", "keys.bin"}});
  j["bufferViews"].push_back({{"buffer", 1}, {"byteLength", keys * 4}});
  j["accessors"].push_back(
      {{"bufferView", 7}, {"componentType", 5126}, {"count", keys}, {"type", "SCALAR"}});
  j["animations"][1]["samplers"][0]["input"] = 7;
  const std::string message = input_error_of(dir.write("huge.gltf", j.dump()));
  EXPECT_NE(message.find("animation 1 'hop' channel 0: the animations have more than 1000000 keys"),
            std::string::npos)
      << message;
}

}  // namespace
}  // namespace farm
