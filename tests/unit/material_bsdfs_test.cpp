#include "renderer/trace/material_bsdfs.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <random>

#include "renderer/accel/prepared_scene.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

// Every material kind the opaque table can hold.
std::vector<Material> assorted_materials(float tint) {
  Material lambert;
  lambert.diffuse = glm::vec3(0.7f, 0.2f, tint);
  lambert.specular = glm::vec3(0.0f);
  Material glossy;
  glossy.diffuse = glm::vec3(0.3f, tint, 0.1f);
  glossy.specular = glm::vec3(0.25f);
  glossy.shininess = 40.0f + 100.0f * tint;
  Material mirror;
  mirror.shininess = 1000.0f;
  mirror.specular = glm::vec3(tint, 0.9f, 0.8f);
  Material metal;
  metal.metal_roughness = MetalRoughness{glm::vec3(0.9f, tint, 0.3f), 0.4f, 0.3f + 0.5f * tint};
  return {lambert, glossy, mirror, metal};
}

// The table's BSDF of a hit is Bsdf(*hit.material, false): the same values, sampled and
// evaluated, for every material of every object, whichever object the hit is on.
TEST(MaterialBsdfs, AHitsBsdfIsTheOneItsOwnMaterialMakes) {
  Scene scene;
  for (int o = 0; o < 3; ++o) {
    SceneObject object = test::object_of(test::make_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}),
                                         glm::translate(glm::mat4(1.0f), glm::vec3(2.0f * o, 0, 0)));
    object.materials = assorted_materials(0.1f + 0.3f * static_cast<float>(o));
    if (o == 1) object.materials.resize(2);  // objects' lists differ in length too
    scene.objects.push_back(std::move(object));
  }
  const PreparedScene prepared(std::move(scene));
  const MaterialBsdfs table(prepared);

  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  int compared = 0;
  for (std::uint32_t o = 0; o < prepared.objects().size(); ++o) {
    const std::vector<Material>& materials = prepared.objects()[o].source->materials;
    for (const Material& material : materials) {
      SurfaceHit hit;
      hit.object = o;
      hit.material = &material;
      const Bsdf& cached = table.opaque(hit);
      const Bsdf made(material, false);
      for (int i = 0; i < 50; ++i) {
        const glm::vec3 wo = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) + 0.05f));
        const glm::vec3 wi = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) + 0.05f));
        EXPECT_EQ(cached.eval(wo, wi), made.eval(wo, wi));
        EXPECT_EQ(cached.pdf(wo, wi), made.pdf(wo, wi));
        EXPECT_EQ(cached.is_specular(), made.is_specular());
        const float a = u(rng), b = u(rng), c = u(rng);
        const auto s = cached.sample(wo, a, b, c), t = made.sample(wo, a, b, c);
        ASSERT_EQ(s.has_value(), t.has_value());
        if (!s) continue;
        EXPECT_EQ(s->wi, t->wi);
        EXPECT_EQ(s->weight, t->weight);
        EXPECT_EQ(s->pdf, t->pdf);
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 300);
}

}  // namespace
}  // namespace farm
