#include "server/bench/embree_direct.h"

#include <stdexcept>
#include <string>

#include "renderer/accel/embree_ray.h"

namespace farm {

struct EmbreeDirect::Handles {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Handles() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void check(const char* step) const {
    const RTCError error = rtcGetDeviceError(device);
    if (error != RTC_ERROR_NONE) throw std::runtime_error(std::string("Embree: ") + step + " failed (error " +
                                                          std::to_string(static_cast<int>(error)) + ")");
  }
};

EmbreeDirect::EmbreeDirect(const PreparedScene& prepared) : handles_(std::make_unique<Handles>()) {
  Handles& h = *handles_;
  h.device = rtcNewDevice(nullptr);
  if (!h.device) throw std::runtime_error("Embree: rtcNewDevice failed");
  h.scene = rtcNewScene(h.device);
  for (const PreparedObject& object : prepared.objects()) {
    const ModelTriangles& mesh = *object.triangles;
    if (mesh.triangles.empty()) continue;
    RTCGeometry geometry = rtcNewGeometry(h.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      const glm::vec3 p = glm::vec3(object.model_to_world * glm::vec4(mesh.positions[i], 1.0f));
      std::copy_n(&p.x, 3, vertices + 3 * i);
    }
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      std::copy_n(&mesh.triangles[t].x, 3, indices + 3 * t);
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(h.scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(h.scene);
  h.check("building the scene");
}

EmbreeDirect::~EmbreeDirect() = default;

bool EmbreeDirect::closest_hit(const Ray& ray) const {
  RTCRayHit query;
  embree_intersect1(handles_->scene, ray, query);
  return query.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

bool EmbreeDirect::occluded(const Ray& ray) const { return embree_occluded1(handles_->scene, ray); }

}  // namespace farm
