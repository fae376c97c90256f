#include "renderer/accel/embree_intersector.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/gtc/type_ptr.hpp>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "renderer/accel/embree_ray.h"
#include "renderer/accel/prepared_scene.h"

namespace farm {
namespace {

struct ReleaseDevice {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
};
struct ReleaseScene {
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
};
struct ReleaseGeometry {
  void operator()(RTCGeometry g) const { rtcReleaseGeometry(g); }
};
using DeviceHandle = std::unique_ptr<RTCDeviceTy, ReleaseDevice>;
using SceneHandle = std::unique_ptr<RTCSceneTy, ReleaseScene>;
using GeometryHandle = std::unique_ptr<RTCGeometryTy, ReleaseGeometry>;

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "unrecognised error";
}

// Embree reports errors through a C callback, which must not throw; it records the message and
// the builder turns it into an exception after the call that failed.
struct ErrorLog {
  std::mutex mutex;
  std::string message;

  static void record(void* self, RTCError code, const char* text) {
    auto* log = static_cast<ErrorLog*>(self);
    std::lock_guard lock(log->mutex);
    if (log->message.empty()) log->message = fmt::format("{}: {}", error_name(code), text ? text : "");
  }
  std::string take() {
    std::lock_guard lock(mutex);
    return std::exchange(message, {});
  }
};

class EmbreeIntersector final : public SceneIntersector {
 public:
  EmbreeIntersector(const PreparedScene& scene, const CancelFlag& cancel);

  bool closest_hit(const Ray& ray, SurfaceHit& hit, TraversalStats* stats) const override;
  bool find_closest(const Ray& ray, SurfaceHit& hit, TraversalStats* stats) const override;
  bool occluded(const Ray& ray, TraversalStats* stats) const override;

 private:
  void check(const char* step);
  SceneHandle new_scene();
  SceneHandle build_model_scene(const ModelTriangles& triangles);

  const PreparedScene& prepared_;
  // The caller's, during the constructor's builds only: the flag does not outlive the call that
  // built the intersector, so nothing refers to it afterwards.
  const CancelFlag* cancel_;
  ErrorLog errors_;
  // Declared first so it is released last, after the scenes that belong to it.
  DeviceHandle device_;
  std::vector<SceneHandle> model_scenes_;
  SceneHandle scene_;
};

void EmbreeIntersector::check(const char* step) {
  // A build the progress callback cancelled fails with RTC_ERROR_CANCELLED: a stop, not an error.
  if (cancel_ && cancel_->reason() != StopReason::None) {
    errors_.take();
    throw RenderStopped(cancel_->reason());
  }
  const RTCError code = rtcGetDeviceError(device_.get());
  std::string message = errors_.take();
  if (code == RTC_ERROR_NONE && message.empty()) return;
  if (message.empty()) message = error_name(code);
  throw std::runtime_error(fmt::format("Embree: {} failed: {}", step, message));
}

SceneHandle EmbreeIntersector::new_scene() {
  SceneHandle scene(rtcNewScene(device_.get()));
  check("creating a scene");
  // Robust mode makes the triangle test watertight, which a reference for our BVH should be.
  rtcSetSceneFlags(scene.get(), RTC_SCENE_FLAG_ROBUST);
  // High quality (spatial splits): built once per model and per job, then traced many times.
  rtcSetSceneBuildQuality(scene.get(), RTC_BUILD_QUALITY_HIGH);
  // Embree asks now and then during a build whether to go on.
  rtcSetSceneProgressMonitorFunction(
      scene.get(), [](void* flag, double) { return !static_cast<const CancelFlag*>(flag)->stop_requested(); },
      const_cast<CancelFlag*>(cancel_));
  return scene;
}

SceneHandle EmbreeIntersector::build_model_scene(const ModelTriangles& model) {
  SceneHandle scene = new_scene();
  if (model.size() > 0 && !model.positions.empty()) {
    GeometryHandle geometry(rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE));
    check("creating a triangle geometry");
    rtcSetGeometryBuildQuality(geometry.get(), RTC_BUILD_QUALITY_HIGH);
    // Embree reads every vertex with a 16-byte load, so the last one needs 4 readable bytes
    // beyond it, which a std::vector<glm::vec3> does not promise: Embree's own buffer is padded.
    void* vertices = rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0,
                                             RTC_FORMAT_FLOAT3, sizeof(glm::vec3),
                                             model.positions.size());
    check("allocating a vertex buffer");
    std::memcpy(vertices, model.positions.data(), model.positions.size() * sizeof(glm::vec3));
    static_assert(sizeof(glm::uvec3) == 3 * sizeof(unsigned int));
    rtcSetSharedGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                               model.triangles.data(), 0, sizeof(glm::uvec3), model.size());
    rtcCommitGeometry(geometry.get());
    check("committing a triangle geometry");
    // geomID 0: hits report primID as the index into ModelTriangles::triangles.
    rtcAttachGeometryByID(scene.get(), geometry.get(), 0);
    check("attaching a triangle geometry");
  }
  rtcCommitScene(scene.get());
  check("building a model's BVH");
  return scene;
}

EmbreeIntersector::EmbreeIntersector(const PreparedScene& prepared, const CancelFlag& cancel)
    : prepared_(prepared), cancel_(&cancel) {
  device_.reset(rtcNewDevice(nullptr));
  if (!device_) {
    throw std::runtime_error(fmt::format("Embree: creating a device failed: {}",
                                         error_name(rtcGetDeviceError(nullptr))));
  }
  rtcSetDeviceErrorFunction(device_.get(), &ErrorLog::record, &errors_);
  if (rtcGetDeviceProperty(device_.get(), RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED) != 0) {
    // Our intersectors hit both sides of a triangle; a culling build would disagree everywhere.
    throw std::runtime_error("Embree: this Embree library was built with back-face culling, "
                             "which the renderer cannot use");
  }

  std::map<const ModelTriangles*, RTCScene> scene_of;
  for (const PreparedObject& object : prepared.objects()) {
    RTCScene& model_scene = scene_of[object.triangles];
    if (!model_scene) {
      model_scenes_.push_back(build_model_scene(*object.triangles));
      model_scene = model_scenes_.back().get();
    }
  }

  scene_ = new_scene();
  const std::vector<PreparedObject>& objects = prepared.objects();
  for (std::size_t i = 0; i < objects.size(); ++i) {
    if (objects[i].triangles->size() == 0) continue;  // nothing to hit; its ID stays unused
    GeometryHandle instance(rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_INSTANCE));
    check("creating an instance");
    rtcSetGeometryInstancedScene(instance.get(), scene_of.at(objects[i].triangles));
    // glm stores matrices column by column, exactly Embree's FLOAT4X4_COLUMN_MAJOR.
    rtcSetGeometryTransform(instance.get(), 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR,
                            glm::value_ptr(objects[i].model_to_world));
    rtcCommitGeometry(instance.get());
    check("committing an instance");
    // Geometry ID = object index, so a hit's instID names the scene object directly.
    rtcAttachGeometryByID(scene_.get(), instance.get(), static_cast<unsigned int>(i));
    check("attaching an instance");
  }
  rtcCommitScene(scene_.get());
  check("building the scene's top-level BVH");
  for (const SceneHandle& built : model_scenes_) rtcSetSceneProgressMonitorFunction(built.get(), nullptr, nullptr);
  rtcSetSceneProgressMonitorFunction(scene_.get(), nullptr, nullptr);
  cancel_ = nullptr;
}

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool EmbreeIntersector::closest_hit(const Ray& ray, SurfaceHit& hit, TraversalStats* stats) const {
  if (!find_closest(ray, hit, stats)) return false;
  complete_surface_hit(prepared_, ray, hit);
  return true;
}

bool EmbreeIntersector::find_closest(const Ray& ray, SurfaceHit& hit, TraversalStats*) const {
  // Embree's behaviour on NaN or infinite rays is undefined unless built to ignore them.
  if (!finite(ray.origin) || !finite(ray.direction)) return false;
  RTCRayHit query;
  embree_intersect1(scene_.get(), ray, query);
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

  hit = SurfaceHit{};
  hit.t = query.ray.tfar;  // the direction is not normalised in the instance either: same units
  hit.object = query.hit.instID[0];
  hit.triangle = query.hit.primID;
  hit.u = query.hit.u;
  hit.v = query.hit.v;
  return true;
}

bool EmbreeIntersector::occluded(const Ray& ray, TraversalStats*) const {
  if (!finite(ray.origin) || !finite(ray.direction)) return false;
  return embree_occluded1(scene_.get(), ray);
}

}  // namespace

std::unique_ptr<SceneIntersector> build_embree_intersector(const PreparedScene& scene,
                                                           const CancelFlag& cancel) {
  return std::make_unique<EmbreeIntersector>(scene, cancel);
}

}  // namespace farm
