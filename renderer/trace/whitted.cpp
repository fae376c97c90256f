#include "renderer/trace/whitted.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <vector>

#include "renderer/accel/scene_intersector.h"
#include "renderer/scene/blinn_phong.h"
#include "renderer/scene/radiance_limit.h"
#include "renderer/scene/shading_normal.h"
#include "renderer/texture/environment_light.h"
#include "renderer/texture/material_textures.h"
#include "renderer/trace/camera_ray_stream.h"
#include "renderer/trace/fresnel.h"
#include "renderer/trace/ray_offset.h"
#include "renderer/trace/ray_tile.h"
#include "renderer/trace/sampler.h"

namespace farm::whitted {
namespace {

// Closest-hit rays (camera rays and their reflections and refractions, each with its shadow rays)
// traced between looks at the cancel flag: well under a millisecond of work.
constexpr int kRaysPerPoll = 64;

// The shading normal on the side the viewer sees: two-sided shading, as in the rasterizer.
glm::vec3 facing_shading_normal(const SurfaceHit& hit, const glm::vec3& to_eye) {
  const glm::vec3& n = hit.shading_normal;
  if (glm::dot(n, to_eye) >= 0.0f) return n;
  return has_normal_map(*hit.material) ? bent_normal_facing(n, hit.geometric_normal, to_eye) : -n;
}

// The ray from `point` (on a surface of geometric normal `ng`) toward a light: only hits before
// the light occlude.
Ray shadow_ray(const glm::vec3& point, const glm::vec3& ng, const LightIncidence& in) {
  Ray shadow;
  shadow.origin = offset_ray_origin(point, ng, in.to_light);
  if (std::isinf(in.distance)) {
    shadow.direction = in.to_light;
  } else {
    // Aim at the light itself: only hits with t < 1 (before the light) occlude.
    shadow.direction = in.to_light * in.distance + (point - shadow.origin);
    shadow.t_max = 1.0f - 1e-4f;
  }
  return shadow;
}

// The shadow rays of a packet of camera rays' hits, traced toward each light together
// (SceneIntersector::occluded_packet): from neighbouring points toward one light they are as
// coherent as the camera rays. Per light, a bit per lane: the lanes whose shading asks for that
// light, and those blocked. Each answer is occluded's for the same ray, so the shading that reads
// it shades as if it had traced the ray itself.
struct PacketShadows {
  std::vector<unsigned> asked, blocked;
};

// What one camera ray's shading reads of its packet's shadows: none (trace them) or a lane.
struct LaneShadows {
  const PacketShadows* packet = nullptr;
  int lane = 0;
};

class WhittedTracer {
 public:
  WhittedTracer(const PreparedScene& scene, const RenderSettings& settings,
                const SceneIntersector& intersector, CancelPoll& poll)
      : prepared_(scene), scene_(scene.scene()), settings_(settings), intersector_(intersector), poll_(poll),
        pixel_size_(scene_.camera.pixel_size_at_unit_depth(settings.height)) {}

  // What a camera ray brings back: its colour, and the first hit's AOVs. Not the hit itself,
  // which a packet's stream keeps (a SurfaceHit in here was zeroed and copied each sample).
  struct Primary {
    glm::vec3 color{0.0f};
    bool hit = false;
    float depth = 0.0f;  // the hit's t
    glm::vec3 facing_normal{0.0f};
    glm::vec3 albedo{0.0f};  // the surface's diffuse colour, textures read
  };

  // The tile's next camera rays, made by ray_of and traced together, and then, when they were a
  // packet, the shadow rays their hits' shading will ask for, a packet per light.
  template <typename RayOf>
  void trace_camera_rays(CameraRayStream& stream, RayOf&& ray_of) const {
    stream.refill(intersector_, ray_of);
    std::fill(shadows_.asked.begin(), shadows_.asked.end(), 0u);
    if (!stream.traced() || !settings_.shadows) return;
    // The side each hit's shading will light, as shade() works it out.
    std::array<glm::vec3, CameraRayStream::kWidth> facing;
    unsigned met = 0;
    for (int lane = 0; lane < CameraRayStream::kWidth; ++lane) {
      const CameraRayHit camera = stream.hit(lane);
      if (!camera.met) continue;
      facing[static_cast<std::size_t>(lane)] =
          facing_shading_normal(*camera.hit, -glm::normalize(stream.ray(lane).direction));
      met |= 1u << lane;
    }
    std::array<Ray, CameraRayStream::kWidth> rays;
    for (std::size_t l = 0; l < scene_.lights.size(); ++l) {
      unsigned asked = 0;
      for (unsigned rest = met; rest; rest &= rest - 1) {
        const int lane = __builtin_ctz(rest);
        const SurfaceHit& hit = *stream.hit(lane).hit;
        // As shade_blinn_phong asks: lights in front of the side seen.
        const LightIncidence in = light_incidence(scene_.lights[l], hit.position);
        if (glm::dot(facing[static_cast<std::size_t>(lane)], in.to_light) <= 0.0f) continue;
        rays[static_cast<std::size_t>(lane)] = shadow_ray(hit.position, hit.geometric_normal, in);
        asked |= 1u << lane;
      }
      shadows_.asked[l] = asked;
      shadows_.blocked[l] = asked ? intersector_.occluded_packet(rays.data(), asked) : 0u;
    }
  }

  // What the shading of the last camera rays' lane `lane` reads of their shadow packets.
  LaneShadows shadows_of(int lane) const { return {&shadows_, lane}; }

  // Closest-hit and shadow rays traced so far.
  std::uint64_t rays_traced() const { return rays_; }
  // Whether the poll said stop: what was traced since is cut short.
  bool stopped() const { return poll_.stopped(); }

  // The first hit is returned too, for the AOVs. Once poll_ says stop, the rays not yet traced
  // are skipped and the colour is meaningless (the caller checks poll_.stopped(), drops the tile).
  // `camera`: the ray's hit when it was found beforehand (camera_ray_stream.h); else it is traced
  // here, its work counted into `stats` (optional).
  // `shadows`: its shadow rays' answers found beforehand, where its packet has them.
  Primary trace_primary(const Ray& ray, const CameraRayHit& camera, const LaneShadows& shadows,
                        TraversalStats* stats) const {
    Primary p;
    if (poll_()) return p;
    ++rays_;
    if (camera.traced) {
      shade_primary(ray, camera.met ? camera.hit : nullptr, shadows, p);
    } else {
      SurfaceHit hit;
      shade_primary(ray, intersector_.closest_hit(ray, hit, stats) ? &hit : nullptr, shadows, p);
    }
    return p;
  }

 private:
  // A camera ray's colour and AOVs from its hit (null: none).
  void shade_primary(const Ray& ray, const SurfaceHit* hit, const LaneShadows& shadows, Primary& p) const {
    if (!hit) {
      p.color = background_radiance(scene_, ray.direction);
      return;
    }
    p.hit = true;
    p.depth = hit->t;
    p.color = shade(ray, *hit, 0, &p.facing_normal, &p.albedo, shadows);
  }

  glm::vec3 trace(const Ray& ray, int depth) const {
    // A deep max_depth through glass doubles the rays at every level: looked at here too.
    if (poll_()) return glm::vec3(0.0f);
    SurfaceHit hit;
    ++rays_;
    if (!intersector_.closest_hit(ray, hit, nullptr)) return background_radiance(scene_, ray.direction);
    return shade(ray, hit, depth, nullptr);
  }

  // Light `light` seen from `point`: its shadow ray's answer from `shadows` when traced
  // beforehand, else traced here.
  bool light_visible(const glm::vec3& point, const glm::vec3& geometric_normal, const LightIncidence& in,
                     std::size_t light, const LaneShadows& shadows) const {
    if (!settings_.shadows) return true;
    ++rays_;
    if (shadows.packet && (shadows.packet->asked[light] >> shadows.lane & 1u)) {
      return (shadows.packet->blocked[light] >> shadows.lane & 1u) == 0;
    }
    return !intersector_.occluded(shadow_ray(point, geometric_normal, in));
  }

  glm::vec3 shade(const Ray& ray, const SurfaceHit& hit, int depth, glm::vec3* facing_normal = nullptr,
                  glm::vec3* albedo = nullptr, const LaneShadows& shadows = {}) const {
    // A camera ray's cone is a pixel wide at the hit's depth; reflected and refracted rays read
    // the textures' finest level.
    Material textured;
    const Material& m = hit_material(prepared_, ray.direction, hit, depth == 0 ? hit.t * pixel_size_ : 0.0f, textured);
    if (albedo) *albedo = m.diffuse;
    const glm::vec3 d = glm::normalize(ray.direction);
    const glm::vec3 to_eye = -d;
    const glm::vec3 n = facing_shading_normal(hit, to_eye);
    if (facing_normal) *facing_normal = n;
    const glm::vec3& ng = hit.geometric_normal;

    const bool front_side = glm::dot(hit.geometric_normal, to_eye) >= 0.0f;
    const float transmitted = m.transmitted_share();
    const bool dielectric = transmitted > 0.0f;
    // A mirror's or glass's reflection of an environment is traced below, not approximated.
    const bool traced = dielectric || m.is_mirror();
    const glm::vec3 local = shade_blinn_phong(
        m, hit.position, n, to_eye, front_side, scene_.lights, ambient_light(scene_, m, n, to_eye, !traced),
        [&](const glm::vec3& p, const LightIncidence& in, std::size_t light) {
          return light_visible(p, ng, in, light, shadows);
        });
    if (depth >= settings_.max_depth || !traced) return local;

    // The normal on the side the ray comes from, and the indices on either side.
    const bool entering = glm::dot(d, ng) < 0.0f;
    glm::vec3 nf = hit.shading_normal;
    if (glm::dot(nf, d) > 0.0f) nf = -nf;
    const float cos_i = std::min(1.0f, -glm::dot(d, nf));
    const float eta_i = entering ? 1.0f : m.ior, eta_t = entering ? m.ior : 1.0f;
    const float reflectance = fresnel_dielectric(cos_i, eta_i, eta_t);

    const glm::vec3 reflected_dir = d + 2.0f * cos_i * nf;
    const glm::vec3 reflected =
        trace(Ray{offset_ray_origin(hit.position, ng, reflected_dir), reflected_dir}, depth + 1);
    if (!dielectric) return local + reflectance * reflected;

    glm::vec3 through(0.0f);
    if (reflectance < 1.0f) {
      // Snell's law in vector form.
      const float eta = eta_i / eta_t;
      const float cos_t = std::sqrt(std::max(0.0f, 1.0f - eta * eta * (1.0f - cos_i * cos_i)));
      const glm::vec3 refracted_dir = eta * d + (eta * cos_i - cos_t) * nf;
      through = m.transmission_tint() *
                trace(Ray{offset_ray_origin(hit.position, ng, refracted_dir), refracted_dir}, depth + 1);
    }
    return (1.0f - transmitted) * local + transmitted * (reflectance * reflected + (1.0f - reflectance) * through);
  }

  const PreparedScene& prepared_;
  const Scene& scene_;
  const RenderSettings& settings_;
  const SceneIntersector& intersector_;
  CancelPoll& poll_;  // counts closest-hit rays; the caller's, so that it sees a stop too
  mutable std::uint64_t rays_ = 0;  // one tracer per tile, so a plain counter
  mutable PacketShadows shadows_{std::vector<unsigned>(scene_.lights.size()), std::vector<unsigned>(scene_.lights.size())};
  float pixel_size_;  // a camera ray's cone width per unit depth (Camera::pixel_size_at_unit_depth)
};

}  // namespace

StopReason render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                       TileBuffer& out, const CancelFlag& cancel) {
  // The variance AOV stays at the zeros reset() writes: a Whitted pixel is no Monte Carlo
  // estimate of the light reaching it (its extra samples only antialias), so there is no noise
  // in it to report.
  const CameraRays camera(scene.scene().camera, settings.width, settings.height);
  const int samples = std::max(1, settings.spp);
  const std::uint64_t seed = frame_seed(settings.seed, settings.frame);
  // The cost AOV counts sample 0's own walk, so that ray is traced alone; the others (all,
  // without the AOV) stream through the tile's packets and each is shaded in its turn.
  const bool counted = settings.aovs.bvh_cost;
  CameraRayStream camera_rays(tile, counted ? 1 : 0, samples);
  // Sample 0 is the pixel centre; further samples are jittered within the pixel.
  const auto camera_ray = [&](int x, int y, int sample) {
    const SampleKey k{seed, pixel_index(settings, x, y), static_cast<std::uint32_t>(sample)};
    const float ox = sample == 0 ? 0.5f : sample_uniform(k, 0), oy = sample == 0 ? 0.5f : sample_uniform(k, 1);
    return camera.ray(static_cast<float>(x) + ox, static_cast<float>(y) + oy);
  };
  return trace_tile(
      scene, settings, tile, out, cancel, kRaysPerPoll,
      [&](const SceneIntersector& intersector, CancelPoll& poll) {
        return WhittedTracer(scene, settings, intersector, poll);
      },
      [&](const WhittedTracer& tracer, int x, int y) {
        glm::vec4 sum(0.0f);
        for (int s = 0; s < samples; ++s) {
          TraversalStats stats;
          const auto primary = [&] {
            if (s == 0 && counted) {
              return tracer.trace_primary(camera_ray(x, y, 0), CameraRayHit{}, LaneShadows{}, &stats);
            }
            if (camera_rays.used_up()) tracer.trace_camera_rays(camera_rays, camera_ray);
            const int lane = camera_rays.take();
            return tracer.trace_primary(camera_rays.ray(lane), camera_rays.hit(lane), tracer.shadows_of(lane), nullptr);
          };
          const WhittedTracer::Primary p = primary();
          if (tracer.stopped()) return false;
          sum += glm::vec4(limit_radiance(p.color), p.hit ? 1.0f : 0.0f);
          if (s != 0) continue;
          if (out.aovs().bvh_cost) out.bvh_cost(x, y) = static_cast<float>(stats.cost());
          if (!p.hit) continue;
          // primary_ray's direction has unit length along the viewing axis, so t is the depth.
          if (out.aovs().depth) out.depth(x, y) = p.depth;
          if (out.aovs().normal) out.normal(x, y) = p.facing_normal;
          if (out.aovs().albedo) out.albedo(x, y) = p.albedo;
        }
        out.rgba(x, y) = sum / static_cast<float>(samples);
        return true;
      });
}

}  // namespace farm::whitted
