#include "server/bench/embree_direct.h"

#include <cmath>
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

namespace {

// Lanes `lanes` of rays[] into Embree's struct of arrays; `valid` marks them (-1) for Embree.
void to_embree8(const Ray* rays, unsigned lanes, int* valid, RTCRay8& out) {
  for (int i = 0; i < 8; ++i) {
    valid[i] = (lanes >> i & 1u) ? -1 : 0;
    RTCRay one;
    to_embree(valid[i] ? rays[i] : Ray{}, one);
    out.org_x[i] = one.org_x;
    out.org_y[i] = one.org_y;
    out.org_z[i] = one.org_z;
    out.dir_x[i] = one.dir_x;
    out.dir_y[i] = one.dir_y;
    out.dir_z[i] = one.dir_z;
    out.tnear[i] = one.tnear;
    out.tfar[i] = one.tfar;
    out.time[i] = one.time;
    out.mask[i] = one.mask;
    out.id[i] = one.id;
    out.flags[i] = one.flags;
  }
}

}  // namespace

unsigned EmbreeDirect::closest_hit8(const Ray* rays, unsigned lanes) const {
  alignas(32) int valid[8];
  alignas(32) RTCRayHit8 query;
  to_embree8(rays, lanes, valid, query.ray);
  for (int i = 0; i < 8; ++i) {
    query.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
    query.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
  }
#if RTC_VERSION_MAJOR >= 4
  rtcIntersect8(valid, handles_->scene, &query);
#else
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect8(valid, handles_->scene, &context, &query);
#endif
  unsigned hit = 0;
  for (int i = 0; i < 8; ++i) {
    if (valid[i] && query.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID) hit |= 1u << i;
  }
  return hit;
}

unsigned EmbreeDirect::occluded8(const Ray* rays, unsigned lanes) const {
  alignas(32) int valid[8];
  alignas(32) RTCRay8 query;
  to_embree8(rays, lanes, valid, query);
#if RTC_VERSION_MAJOR >= 4
  rtcOccluded8(valid, handles_->scene, &query);
#else
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded8(valid, handles_->scene, &context, &query);
#endif
  // Embree marks a blocked ray by setting its tfar to -inf.
  unsigned blocked = 0;
  for (int i = 0; i < 8; ++i) {
    if (valid[i] && query.tfar[i] == -INFINITY) blocked |= 1u << i;
  }
  return blocked;
}

}  // namespace farm
