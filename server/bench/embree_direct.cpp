#include "server/bench/embree_direct.h"

#if __has_include(<embree4/rtcore.h>)
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

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

namespace {

void set_ray(const Ray& in, RTCRay& out) {
  out.org_x = in.origin.x;
  out.org_y = in.origin.y;
  out.org_z = in.origin.z;
  out.dir_x = in.direction.x;
  out.dir_y = in.direction.y;
  out.dir_z = in.direction.z;
  out.tnear = std::max(in.t_min, 0.0f);
  out.tfar = in.t_max;
  out.time = 0.0f;
  out.mask = ~0u;
  out.id = 0;
  out.flags = 0;
}

}  // namespace

bool EmbreeDirect::closest_hit(const Ray& ray) const {
  RTCRayHit query;
  set_ray(ray, query.ray);
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
#if RTC_VERSION_MAJOR >= 4
  rtcIntersect1(handles_->scene, &query);
#else
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect1(handles_->scene, &context, &query);
#endif
  return query.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

bool EmbreeDirect::occluded(const Ray& ray) const {
  RTCRay query;
  set_ray(ray, query);
#if RTC_VERSION_MAJOR >= 4
  rtcOccluded1(handles_->scene, &query);
#else
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded1(handles_->scene, &context, &query);
#endif
  return query.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace farm
