#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <utility>

#include "renderer/accel/prepared_scene.h"
#include "renderer/trace/emitter_facing.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

using test::make_box;
using test::make_quad;
using test::make_sphere;
using test::object_of;

Material lamp_material(EmissionSides sides = EmissionSides::Front) {
  Material m;
  m.name = "lamp";
  m.emission = glm::vec3(10.0f);
  m.emission_sides = sides;
  return m;
}

// The model turned inside out: winding (and normals) reversed.
Model flipped(Model model) {
  for (Mesh& mesh : model.meshes) {
    for (glm::uvec3& t : mesh.triangles) std::swap(t.y, t.z);
    for (glm::vec3& n : mesh.normals) n = -n;
  }
  return model;
}

// A closed room of [-1, 1]^3 wound to face inwards, and a 0.5 x 0.5 lamp `gap` under its
// ceiling, facing down into it (or up into the ceiling, flipped).
std::vector<EmitterFacingAway> room_with_lamp(float gap, bool lamp_flipped, EmissionSides sides = EmissionSides::Front,
                                              const glm::mat4& lamp_to_world = glm::mat4(1.0f)) {
  Scene scene;
  Material walls;
  walls.name = "walls";
  scene.objects.push_back(object_of(flipped(make_box({-1, -1, -1}, {1, 1, 1})), glm::mat4(1.0f), walls));
  const float y = 1.0f - gap;
  Model lamp = make_quad({-0.25f, y, -0.25f}, {0.25f, y, -0.25f}, {0.25f, y, 0.25f}, {-0.25f, y, 0.25f});
  if (lamp_flipped) lamp = flipped(std::move(lamp));
  scene.objects.push_back(object_of(std::move(lamp), lamp_to_world, lamp_material(sides)));
  scene.objects.back().name = "ceiling_lamp";
  const PreparedScene prepared(std::move(scene));
  return find_emitters_facing_away(prepared);
}

TEST(EmitterFacing, ALampJustUnderTheCeilingShiningIntoTheRoomIsFine) {
  for (float gap : {0.001f, 0.01f, 0.3f}) EXPECT_TRUE(room_with_lamp(gap, false).empty()) << gap;
}

TEST(EmitterFacing, TheSameLampFlippedShinesIntoTheCeilingAndIsNamed) {
  for (float gap : {0.001f, 0.01f, 0.1f}) {
    const auto found = room_with_lamp(gap, true);
    ASSERT_EQ(found.size(), 1u) << gap;
    EXPECT_EQ(found[0].object, "ceiling_lamp");
    EXPECT_EQ(found[0].material, "lamp");
    EXPECT_EQ(found[0].facing_away, 2u);
    EXPECT_EQ(found[0].checked, 2u);
  }
}

TEST(EmitterFacing, ALampShiningBothWaysIsNeverReported) {
  EXPECT_TRUE(room_with_lamp(0.01f, true, EmissionSides::Both).empty());
}

TEST(EmitterFacing, AMirroringTransformIsJudgedByTheFrontItLeaves) {
  // Mirrored through the lamp's own plane (y = 0.99): the model's front, up, stays up, on the
  // surface's same side... which the mirror turns to face down in the world. The normal matrix
  // says so; the world edges' winding would say the opposite.
  const glm::mat4 mirror = glm::translate(glm::mat4(1.0f), glm::vec3(0, 0.99f, 0)) *
                           glm::scale(glm::mat4(1.0f), glm::vec3(1, -1, 1)) *
                           glm::translate(glm::mat4(1.0f), glm::vec3(0, -0.99f, 0));
  EXPECT_TRUE(room_with_lamp(0.01f, true, EmissionSides::Front, mirror).empty());
  EXPECT_EQ(room_with_lamp(0.01f, false, EmissionSides::Front, mirror).size(), 1u);
}

TEST(EmitterFacing, ALampAboveAFloorShiningAtTheSkyIsReported) {
  for (bool lamp_flipped : {false, true}) {
    Scene scene;
    scene.objects.push_back(object_of(make_quad({-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, {-3, 0, -3})));
    Model lamp = make_quad({-0.5f, 2, -0.5f}, {0.5f, 2, -0.5f}, {0.5f, 2, 0.5f}, {-0.5f, 2, 0.5f});  // faces down
    if (lamp_flipped) lamp = flipped(std::move(lamp));
    scene.objects.push_back(object_of(std::move(lamp), glm::mat4(1.0f), lamp_material()));
    EXPECT_EQ(find_emitters_facing_away(PreparedScene(std::move(scene))).size(), lamp_flipped ? 1u : 0u);
  }
}

TEST(EmitterFacing, AGlowingBallIsJudgedAsAWholeByWhereItsNormalsPoint) {
  for (bool inside_out : {false, true}) {
    Scene scene;
    Material walls;
    scene.objects.push_back(object_of(flipped(make_box({-2, -2, -2}, {2, 2, 2})), glm::mat4(1.0f), walls));
    Model ball = make_sphere(12, 24);
    if (inside_out) ball = flipped(std::move(ball));
    scene.objects.push_back(object_of(std::move(ball), glm::scale(glm::mat4(1.0f), glm::vec3(0.3f)), lamp_material()));
    const auto found = find_emitters_facing_away(PreparedScene(std::move(scene)));
    ASSERT_EQ(found.size(), inside_out ? 1u : 0u);
    if (inside_out) {
      EXPECT_EQ(found[0].facing_away, found[0].checked);
    }
  }
  // Alone, either way may be meant (a glowing ball, or a dome around the camera): no warning.
  for (bool inside_out : {false, true}) {
    Scene scene;
    Model ball = make_sphere(12, 24);
    if (inside_out) ball = flipped(std::move(ball));
    scene.objects.push_back(object_of(std::move(ball), glm::mat4(1.0f), lamp_material()));
    EXPECT_TRUE(find_emitters_facing_away(PreparedScene(std::move(scene))).empty()) << inside_out;
  }
}

TEST(EmitterFacing, ASceneWithoutFrontOnlyEmittersHasNothingToReport) {
  Scene scene;
  scene.objects.push_back(object_of(make_box({-1, -1, -1}, {1, 1, 1})));
  EXPECT_TRUE(find_emitters_facing_away(PreparedScene(std::move(scene))).empty());
}

}  // namespace
}  // namespace farm
