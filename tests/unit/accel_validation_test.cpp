// validate_accel: a deterministic ray set, and disagreements reported with the right counts.
// Embree serves as both sides here; wrappers break it in known ways.
#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <mutex>
#include <vector>

#include "renderer/accel/accel_validation.h"
#include "renderer/accel/embree_intersector.h"
#include "renderer/accel/prepared_scene.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

Scene two_object_scene() {
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_sphere(16, 24),
                                          glm::scale(glm::mat4(1.0f), glm::vec3(1.0f, 0.6f, 1.2f))));
  scene.objects.push_back(test::object_of(
      test::make_box({-3, -1.5f, -3}, {3, -1.2f, 3}),
      glm::rotate(glm::mat4(1.0f), glm::radians(10.0f), glm::vec3(0, 0, 1))));
  // Farther than the scene is wide, so primary rays' t differences are relative to t itself.
  scene.camera.position = {1.5f, 3.0f, 18.0f};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 15.0f;
  return scene;
}

RenderSettings settings(int threads = 0) {
  RenderSettings s;
  s.width = 64;
  s.height = 48;
  s.seed = 7;
  s.threads = threads;
  return s;
}

// A per-ray choice that does not depend on the order in which threads query.
std::uint32_t ray_hash(const Ray& ray) {
  std::uint32_t h = 2166136261u;
  for (float f : {ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y,
                  ray.direction.z}) {
    h = (h ^ std::bit_cast<std::uint32_t>(f)) * 16777619u;
  }
  return h ^ (h >> 15);
}

// Wraps a correct intersector and changes some of its hits; counts what it changed.
class Broken : public SceneIntersector {
 public:
  enum class Fault { DropEveryTenth, StretchT, NudgeT, OtherTriangleFarther, OtherTriangleSameT };
  Broken(const SceneIntersector& inner, Fault fault) : inner_(inner), fault_(fault) {}

  bool closest_hit(const Ray& ray, SurfaceHit& hit, TraversalStats* stats) const override {
    if (!inner_.closest_hit(ray, hit, stats)) return false;
    const bool chosen = ray_hash(ray) % 10 == 0;
    switch (fault_) {
      case Fault::DropEveryTenth:
        if (!chosen) return true;
        ++changed;
        return false;
      case Fault::StretchT:
        ++changed;
        hit.t *= 1.001f;
        return true;
      case Fault::NudgeT:
        ++changed;
        hit.t += 1e-6f;
        return true;
      case Fault::OtherTriangleFarther:
      case Fault::OtherTriangleSameT:
        if (!chosen) return true;
        ++changed;
        hit.triangle += 1;
        if (fault_ == Fault::OtherTriangleFarther) hit.t += 0.1f;  // well beyond a tie anywhere
        return true;
    }
    return true;
  }
  bool occluded(const Ray& ray, TraversalStats* stats) const override { return inner_.occluded(ray, stats); }

  mutable std::atomic<std::uint64_t> changed{0};

 private:
  const SceneIntersector& inner_;
  Fault fault_;
};

// Records every ray it is asked about.
class Recorder : public SceneIntersector {
 public:
  explicit Recorder(const SceneIntersector& inner) : inner_(inner) {}
  bool closest_hit(const Ray& ray, SurfaceHit& hit, TraversalStats* stats) const override {
    std::lock_guard lock(mutex_);
    rays.push_back(ray);
    return inner_.closest_hit(ray, hit, stats);
  }
  bool occluded(const Ray& ray, TraversalStats* stats) const override { return inner_.occluded(ray, stats); }

  mutable std::vector<Ray> rays;

 private:
  const SceneIntersector& inner_;
  mutable std::mutex mutex_;
};

class AccelValidationTest : public ::testing::Test {
 protected:
  AccelValidationTest() : scene_(two_object_scene()), embree_(build_embree_intersector(scene_)) {}
  PreparedScene scene_;
  std::unique_ptr<SceneIntersector> embree_;
};

TEST_F(AccelValidationTest, AnIntersectorAgreesWithItselfExactly) {
  const auto other = build_embree_intersector(scene_);
  const AccelValidation v = validate_accel(scene_, settings(), *embree_, *other, 20000);
  EXPECT_EQ(v.rays, 20000u);
  EXPECT_EQ(v.hit_miss_disagreements, 0u);
  EXPECT_EQ(v.triangle_disagreements, 0u);
  EXPECT_EQ(v.max_relative_t_difference, 0.0);
  EXPECT_EQ(v.mean_relative_t_difference, 0.0);
  EXPECT_EQ(v.summary(),
            "embree validation: 20000 rays, 0 hit/miss and 0 triangle disagreements, "
            "max relative t difference 0 (mean 0)");
}

TEST_F(AccelValidationTest, TheSameInputsGiveTheSameResultWhateverTheThreadCount) {
  const Broken stretched(*embree_, Broken::Fault::StretchT);
  const Broken dropping(*embree_, Broken::Fault::DropEveryTenth);
  for (const SceneIntersector* ours : {static_cast<const SceneIntersector*>(&stretched),
                                       static_cast<const SceneIntersector*>(&dropping)}) {
    const AccelValidation one = validate_accel(scene_, settings(1), *ours, *embree_, 10001);
    const AccelValidation again = validate_accel(scene_, settings(1), *ours, *embree_, 10001);
    const AccelValidation two = validate_accel(scene_, settings(2), *ours, *embree_, 10001);
    for (const AccelValidation& other : {again, two}) {
      EXPECT_EQ(one.summary(), other.summary());
      EXPECT_EQ(one.hit_miss_disagreements, other.hit_miss_disagreements);
      EXPECT_EQ(one.max_relative_t_difference, other.max_relative_t_difference);
      EXPECT_EQ(one.mean_relative_t_difference, other.mean_relative_t_difference);  // bit for bit
    }
    EXPECT_NE(one.summary().find("10001 rays"), std::string::npos) << one.summary();
  }
}

TEST_F(AccelValidationTest, HalfThePrimaryRaysStartAtTheCameraTheRestInsideTheSceneBounds) {
  const Recorder recorder(*embree_);
  validate_accel(scene_, settings(), recorder, *embree_, 1001);
  ASSERT_EQ(recorder.rays.size(), 1001u);
  const glm::vec3 eye = scene_.scene().camera.position;
  const glm::vec3 forward = scene_.scene().camera.forward();
  int primary = 0, secondary = 0, along_z = 0, low_x = 0;
  for (const Ray& ray : recorder.rays) {
    if (ray.origin == eye) {
      ++primary;
      // Inside the 15 degree (vertical) frustum.
      EXPECT_GT(glm::dot(glm::normalize(ray.direction), forward), 0.97f);
    } else {
      ++secondary;
      // The box, tilted 10 degrees about z, spans the scene; the sphere lies inside it in x, z.
      EXPECT_TRUE(std::fabs(ray.origin.x) <= 3.3f && ray.origin.y >= -2.1f &&
                  ray.origin.y <= 0.7f && std::fabs(ray.origin.z) <= 3.0f)
          << ::testing::PrintToString(ray.origin);
      low_x += ray.origin.x < -2.5f ? 1 : 0;
      EXPECT_NEAR(glm::length(ray.direction), 1.0f, 1e-5f);
      along_z += ray.direction.z > 0.0f ? 1 : 0;
    }
  }
  EXPECT_EQ(primary, 500);
  EXPECT_EQ(secondary, 501);
  EXPECT_NEAR(along_z, 250, 60);  // directions cover the sphere, not a hemisphere
  EXPECT_GT(low_x, 20);           // origins fill the bounds
}

TEST_F(AccelValidationTest, DroppedHitsCountAsHitMissDisagreements) {
  const Broken broken(*embree_, Broken::Fault::DropEveryTenth);
  const AccelValidation v = validate_accel(scene_, settings(), broken, *embree_, 20000);
  EXPECT_GT(broken.changed.load(), 500u);
  EXPECT_EQ(v.hit_miss_disagreements, broken.changed.load());
  EXPECT_EQ(v.triangle_disagreements, 0u);
  EXPECT_EQ(v.max_relative_t_difference, 0.0);
}

TEST_F(AccelValidationTest, StretchedDistancesShowAsRelativeTDifference) {
  const Broken broken(*embree_, Broken::Fault::StretchT);
  const AccelValidation v = validate_accel(scene_, settings(), broken, *embree_, 20000);
  EXPECT_GT(broken.changed.load(), 5000u);
  EXPECT_EQ(v.hit_miss_disagreements, 0u);
  EXPECT_EQ(v.triangle_disagreements, 0u);
  // Primary rays hit farther away than the scene is wide: exactly the stretch. Secondary hits
  // nearer than that count relative to the scene's size, so they show less.
  EXPECT_NEAR(v.max_relative_t_difference, 1e-3, 1e-6);
  EXPECT_GT(v.mean_relative_t_difference, 2e-4);
  EXPECT_LT(v.mean_relative_t_difference, 1e-3);
}

TEST_F(AccelValidationTest, TinyDifferencesNearTheOriginAreMeasuredAgainstTheScenesSize) {
  // 1e-6 on a hit 1e-6 from the origin is 100% of t, but only float noise for a scene 7 wide.
  const Broken broken(*embree_, Broken::Fault::NudgeT);
  const AccelValidation v = validate_accel(scene_, settings(), broken, *embree_, 20000);
  EXPECT_EQ(v.triangle_disagreements, 0u);
  EXPECT_GT(v.max_relative_t_difference, 0.0);
  EXPECT_LT(v.max_relative_t_difference, 1e-6 / 6.0);
}

TEST_F(AccelValidationTest, AnotherTriangleAtAnotherDistanceIsATriangleDisagreement) {
  const Broken broken(*embree_, Broken::Fault::OtherTriangleFarther);
  const AccelValidation v = validate_accel(scene_, settings(), broken, *embree_, 20000);
  EXPECT_GT(broken.changed.load(), 500u);
  EXPECT_EQ(v.triangle_disagreements, broken.changed.load());
  EXPECT_EQ(v.hit_miss_disagreements, 0u);
  EXPECT_EQ(v.max_relative_t_difference, 0.0);  // counted once, not again as a t difference
}

TEST_F(AccelValidationTest, AnotherTriangleAtTheSameDistanceIsATieNotADisagreement) {
  const Broken broken(*embree_, Broken::Fault::OtherTriangleSameT);
  const AccelValidation v = validate_accel(scene_, settings(), broken, *embree_, 20000);
  EXPECT_GT(broken.changed.load(), 500u);
  EXPECT_EQ(v.triangle_disagreements, 0u);
  EXPECT_EQ(v.max_relative_t_difference, 0.0);
}

TEST_F(AccelValidationTest, NoRaysIsAnEmptyReport) {
  const AccelValidation v = validate_accel(scene_, settings(), *embree_, *embree_, 0);
  EXPECT_EQ(v.rays, 0u);
  EXPECT_EQ(v.hit_miss_disagreements + v.triangle_disagreements, 0u);
}

}  // namespace
}  // namespace farm
