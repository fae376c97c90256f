#include "renderer/trace/path_tracer.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <memory>
#include <optional>

#include "renderer/accel/scene_intersector.h"
#include "renderer/scene/radiance_limit.h"
#include "renderer/scene/shading_normal.h"
#include "renderer/texture/environment_light.h"
#include "renderer/texture/material_textures.h"
#include "renderer/trace/bsdf.h"
#include "renderer/trace/camera_ray_stream.h"
#include "renderer/trace/emitters.h"
#include "renderer/trace/material_bsdfs.h"
#include "renderer/trace/ray_offset.h"
#include "renderer/trace/ray_tile.h"
#include "renderer/trace/sample_warp.h"
#include "renderer/trace/sampler.h"

namespace farm::path {
namespace {

// Bounces traced in full before Russian roulette may stop a path (Mitsuba's rr_depth 3, which
// tools/mitsuba_reference.py sets to match: keep the two equal).
constexpr int kRouletteStart = 3;
// Path segments (closest-hit rays, each with its shadow rays) traced between looks at the cancel
// flag: tens of microseconds of work, so a cancelled tile stops within a millisecond whatever its
// spp, and the look (a clock read when there is a deadline) costs nothing measurable.
constexpr int kSegmentsPerPoll = 32;

float power_heuristic(float f, float g) {
  const float f2 = f * f, g2 = g * g;
  return f2 + g2 > 0.0f ? f2 / (f2 + g2) : 0.0f;
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The variance of a pixel's mean estimate, from its own samples in sample order (Welford's
// update, in double): the same samples give the same bits whatever the tiling or thread.
class SampleVariance {
 public:
  void add(const glm::vec3& x) {
    ++n_;
    const glm::dvec3 v(x), delta = v - mean_;
    mean_ += delta / static_cast<double>(n_);
    m2_ += delta * (v - mean_);
  }
  // Unbiased sample variance over n, the variance of the mean of n samples; 0 for one sample.
  glm::vec3 of_mean() const {
    if (n_ < 2) return glm::vec3(0.0f);
    const double n = static_cast<double>(n_);
    return glm::vec3(m2_ / ((n - 1.0) * n));
  }

 private:
  std::uint64_t n_ = 0;
  glm::dvec3 mean_{0.0}, m2_{0.0};
};

class PathTracer {
 public:
  PathTracer(const PreparedScene& scene, const RenderSettings& settings,
             const SceneIntersector& intersector, std::shared_ptr<const Emitters> emitters,
             std::shared_ptr<const MaterialBsdfs> bsdfs, CancelPoll& poll)
      : scene_(scene), settings_(settings), intersector_(intersector), emitters_(std::move(emitters)),
        bsdfs_(std::move(bsdfs)), poll_(poll), environment_(scene.scene().environment.get()),
        next_event_estimation_(settings.light_sampling == LightSampling::NeeMis),
        pixel_size_(scene.scene().camera.pixel_size_at_unit_depth(settings.height)) {}

  struct Result {
    glm::vec3 radiance{0.0f};
    bool hit = false;
    float first_depth = 0.0f;  // the first hit's t: the depth (a camera ray is unit long along the view)
    glm::vec3 first_normal{0.0f};
    glm::vec3 first_albedo{0.0f};  // its diffuse colour, textures read
  };

  // The tile's next camera rays, made by ray_of and traced together.
  template <typename RayOf>
  void trace_camera_rays(CameraRayStream& stream, RayOf&& ray_of) const {
    stream.refill(intersector_, ray_of);
  }

  // Closest-hit and shadow rays traced so far.
  std::uint64_t rays_traced() const { return rays_; }
  // Whether the poll said stop: what was traced since is cut short.
  bool stopped() const { return poll_.stopped(); }

  // Ends the path early, its value meaningless, once poll_ says stop (the caller checks
  // poll_.stopped() and drops the tile).
  // Always inlined into the sample loop (render_tile): GCC's choice moved with the unity unit this
  // file shares (its inlining budget grows with the unit), and a file added before it once left
  // a call per sample and 6% fewer samples per second, with no change to this code.
  // `camera`: the camera ray's hit when it was found beforehand (camera_ray_stream.h).
  __attribute__((always_inline)) Result trace(Ray ray, const PixelSamples& pixel, std::uint32_t sample,
                                              const CameraRayHit& camera) const {
    Result result;
    glm::vec3 beta(1.0f);
    bool after_specular = true;  // emission seen directly or through mirrors counts in full
    float previous_pdf = 0.0f;
    glm::vec3 previous_position = ray.origin;
    std::uint32_t dim = 2;  // 0 and 1 placed the sample in the pixel
    // Always inlined: when the loop grew (textures), GCC stopped inlining this lambda, and a call
    // per random number cost 6% of the Cornell box's samples per second.
    const auto next = [&]() __attribute__((always_inline)) { return pixel.uniform(sample, dim++); };

    for (int bounce = 0;; ++bounce) {
      if (poll_()) break;
      SurfaceHit hit;
      ++rays_;
      bool met;
      if (bounce == 0 && camera.traced) {
        met = camera.met;
        if (met) hit = *camera.hit;
      } else {
        met = intersector_.closest_hit(ray, hit);
      }
      if (!met) {
        result.radiance += beta * (environment_ ? environment_met(ray, after_specular, previous_pdf)
                                                : scene_.scene().background);  // constant, never sampled
        break;
      }
      // A camera ray's cone is a pixel wide at the hit's depth; later rays read the finest level
      // (their many samples average it).
      const Material& material =
          hit_material(scene_, ray.direction, hit, bounce == 0 ? hit.t * pixel_size_ : 0.0f, textured_);
      const glm::vec3 wo_world = -glm::normalize(ray.direction);
      if (bounce == 0) {
        result.hit = true;
        result.first_depth = hit.t;
        result.first_albedo = material.diffuse;
        result.first_normal = glm::dot(hit.shading_normal, wo_world) < 0.0f ? -hit.shading_normal
                                                                            : hit.shading_normal;
      }

      // Emission met by BSDF sampling, weighted against next-event estimation's chance of it.
      // A front-only emitter seen from behind is dark (its back is an ordinary surface).
      const glm::vec3 le = material.emitted(glm::dot(hit.geometric_normal, wo_world) >= 0.0f);
      if (le != glm::vec3(0.0f)) {
        float weight = 1.0f;
        if (!after_specular && next_event_estimation_) {
          const glm::vec3 d = hit.position - previous_position;
          const float cos_light = std::fabs(glm::dot(hit.geometric_normal, glm::normalize(d)));
          const float light_pdf = cos_light > 0.0f
                                      ? emitters_->pdf_area(hit.object, hit.triangle) * glm::dot(d, d) / cos_light
                                      : 0.0f;
          weight = power_heuristic(previous_pdf, light_pdf);
        }
        result.radiance += beta * le * weight;
      }
      if (settings_.max_depth >= 0 && bounce >= settings_.max_depth) break;

      // A partly transmissive surface is glass or the rest, picked by the glass's share (a number
      // drawn only for such a surface: every other scene's samples stay the ones they were).
      const float transmitted = material.transmitted_share();
      const bool dielectric = transmitted >= 1.0f || (transmitted > 0.0f && next() < transmitted);
      const Bsdf& bsdf = !dielectric && &material == hit.material ? bsdfs_->opaque(hit)
                                                                   : bsdf_.emplace(material, dielectric);
      // The shading frame on the side the ray arrives from (for dielectrics: the geometric
      // side decides inside or outside).
      glm::vec3 n = hit.shading_normal;
      if (glm::dot(n, hit.geometric_normal) < 0.0f) n = -n;
      if (!dielectric && glm::dot(n, wo_world) < 0.0f) {
        n = has_normal_map(*hit.material) ? bent_normal_facing(n, hit.geometric_normal, wo_world) : -n;
      }
      const ShadingFrame frame(n);
      const glm::vec3 wo = frame.to_local(wo_world);

      if (next_event_estimation_ && !bsdf.is_specular()) {
        result.radiance += beta * direct_light(hit, frame, bsdf, wo, next);
      }

      const float u_lobe = next(), u1 = next(), u2 = next();
      BsdfSample s;
      if (!bsdf.sample(wo, u_lobe, u1, u2, s)) break;
      beta *= s.weight;
      after_specular = s.specular;
      previous_pdf = s.pdf;
      previous_position = hit.position;
      const glm::vec3 wi = frame.to_world(s.wi);
      ray = Ray{offset_ray_origin(hit.position, hit.geometric_normal, wi), wi};

      // Russian roulette, for unbounded paths only: continue with a probability that follows the
      // throughput, and make up for the paths it ends by weighting the survivors, so the mean is
      // unchanged. A fixed max_depth is honoured exactly instead.
      if (settings_.max_depth < 0 && bounce + 1 >= kRouletteStart) {
        const float survive = std::min(0.95f, std::max({beta.x, beta.y, beta.z}));
        if (next() >= survive) break;
        beta *= 1.0f / survive;
      }
      if (beta == glm::vec3(0.0f)) break;
    }
    return result;
  }

 private:
  template <typename Next>
  glm::vec3 direct_light(const SurfaceHit& hit, const ShadingFrame& frame, const Bsdf& bsdf,
                         const glm::vec3& wo, Next&& next) const {
    glm::vec3 sum(0.0f);
    // One point on the area lights, weighted against BSDF sampling.
    const float u_pick = next(), u1 = next(), u2 = next();
    if (!emitters_->empty()) {
      const EmitterSample light = emitters_->sample(u_pick, u1, u2);
      const glm::vec3 d = light.position - hit.position;
      const float dist2 = glm::dot(d, d);
      const glm::vec3 wi_world = d * (1.0f / std::sqrt(dist2));  // one division, not three
      // The light leaves the emitter along -wi_world: a point picked on the back of a front-only
      // emitter sends nothing this way. The pick itself ignores the side, so its pdf (and the MIS
      // weight, the same pdf BSDF sampling's hits use) is unchanged: unbiased either way.
      const float cos_out = -glm::dot(light.normal, wi_world);
      const float cos_light = light.two_sided ? std::fabs(cos_out) : cos_out;
      const glm::vec3 wi = frame.to_local(wi_world);
      const glm::vec3 f = bsdf.eval(wo, wi) * std::fabs(wi.z);
      if (cos_light > 0.0f && f != glm::vec3(0.0f) && visible(hit, light.position)) {
        const float light_pdf = light.pdf_area * dist2 / cos_light;
        sum += f * light.radiance * (power_heuristic(light_pdf, bsdf.pdf(wo, wi)) / light_pdf);
      }
    }
    // One direction of the environment, by its luminance, weighted against BSDF sampling. Its
    // numbers are drawn only in a scene with an environment: every other scene's samples stay
    // the ones they were.
    if (environment_) {
      const float e1 = next(), e2 = next();
      sum += environment_sampled(hit, frame, bsdf, wo, e1, e2);
    }
    // Point lights: delta lights, nothing for BSDF sampling to find.
    for (const Light& light : scene_.scene().lights) {
      const bool directional = light.kind == Light::Kind::Directional;
      glm::vec3 wi_world;
      glm::vec3 irradiance = light.intensity;
      if (directional) {
        wi_world = -glm::normalize(light.direction);
      } else {
        const glm::vec3 d = light.position - hit.position;
        wi_world = glm::normalize(d);
        irradiance /= glm::dot(d, d);
      }
      const glm::vec3 wi = frame.to_local(wi_world);
      const glm::vec3 f = bsdf.eval(wo, wi) * std::fabs(wi.z);
      if (f == glm::vec3(0.0f)) continue;
      if (directional ? open_towards(hit, wi_world) : visible(hit, light.position)) sum += f * irradiance;
    }
    return sum;
  }

  // The environment light's part of the two strategies, out of line: the loop of scenes without
  // one stays as small as it was (inlined, this cost the Cornell box 5% of its samples a second).
  // What a ray that left the scene brings back, weighted against next-event estimation's chance
  // of the same direction, as for an emitter hit.
  [[gnu::noinline]] glm::vec3 environment_met(const Ray& ray, bool after_specular, float previous_pdf) const {
    float weight = 1.0f;
    if (!after_specular && next_event_estimation_) {
      weight = power_heuristic(previous_pdf, environment_->pdf(glm::normalize(ray.direction)));
    }
    return environment_->radiance(ray.direction) * weight;
  }
  // One direction picked by the environment's luminance, weighted against BSDF sampling.
  [[gnu::noinline]] glm::vec3 environment_sampled(const SurfaceHit& hit, const ShadingFrame& frame, const Bsdf& bsdf,
                                                  const glm::vec3& wo, float u1, float u2) const {
    const auto light = environment_->sample(u1, u2);
    if (!light) return glm::vec3(0.0f);
    const glm::vec3 wi = frame.to_local(light->direction);
    const glm::vec3 f = bsdf.eval(wo, wi) * std::fabs(wi.z);
    if (f == glm::vec3(0.0f) || !open_towards(hit, light->direction)) return glm::vec3(0.0f);
    return f * light->radiance * power_heuristic(light->pdf, bsdf.pdf(wo, wi)) / light->pdf;
  }

  // Whether nothing lies in the way from `from` along the unit `direction`, out of the scene. (A
  // point "far away" instead, 1e30 along it, made every hit's t too small to count, and the
  // squared length overflow: nothing ever shadowed a directional light that way.)
  bool open_towards(const SurfaceHit& from, const glm::vec3& direction) const {
    Ray shadow;
    shadow.origin = offset_ray_origin(from.position, from.geometric_normal, direction);
    shadow.direction = direction;
    ++rays_;
    return !intersector_.occluded(shadow);
  }

  bool visible(const SurfaceHit& from, const glm::vec3& to) const {
    Ray shadow;
    shadow.origin = offset_ray_origin(from.position, from.geometric_normal, to - from.position);
    shadow.direction = to - shadow.origin;
    shadow.t_max = 1.0f - 1e-3f;  // stop short of the light's own surface
    ++rays_;
    return !intersector_.occluded(shadow);
  }

  const PreparedScene& scene_;
  const RenderSettings& settings_;
  const SceneIntersector& intersector_;
  std::shared_ptr<const Emitters> emitters_;  // the frame cache's, kept alive while this traces
  std::shared_ptr<const MaterialBsdfs> bsdfs_;  // the same
  CancelPoll& poll_;  // counts path segments; the caller's, so that it sees a stop too
  const EnvironmentLight* environment_;  // the scene's; null: the constant background
  bool next_event_estimation_;
  float pixel_size_;  // a camera ray's cone width per unit depth (Camera::pixel_size_at_unit_depth)
  // The hit's material with its textures read (hit_material): one per tracer, which one tile's
  // thread uses, so that trace() holds no object to construct and destroy per path.
  mutable Material textured_;
  // The BSDF of a hit whose material is not one of MaterialBsdfs' (textured, or glass).
  mutable std::optional<Bsdf> bsdf_;
  mutable std::uint64_t rays_ = 0;  // one tracer per tile, so a plain counter
};

}  // namespace

StopReason render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                       TileBuffer& out, const CancelFlag& cancel) {
  const CameraRays camera(scene.scene().camera, settings.width, settings.height);
  // This call's samples of each pixel: a pass's, or all spp. Indices are global within the pixel
  // (pass 1 starts at pass_spp), so the sampler never repeats a sample between passes.
  const SampleRange range = samples_to_render(settings);
  const std::uint64_t seed = frame_seed(settings.seed, settings.frame);
  // The tile's camera rays, traced ahead a packet at a time.
  CameraRayStream camera_rays(tile, range.begin, range.end);
  // The pixel whose numbers were worked out last: its samples come in a row.
  std::uint64_t numbered = ~std::uint64_t{0};
  PixelSamples numbers(seed, numbered);
  const auto camera_ray = [&](int x, int y, int s) {
    if (const std::uint64_t index = pixel_index(settings, x, y); index != numbered) {
      numbers = PixelSamples(seed, index);
      numbered = index;
    }
    const auto sample = static_cast<std::uint32_t>(s);
    // Box filter: the sample lands uniformly anywhere in the pixel.
    return camera.ray(static_cast<float>(x) + numbers.uniform(sample, 0), static_cast<float>(y) + numbers.uniform(sample, 1));
  };
  return trace_tile(
      scene, settings, tile, out, cancel, kSegmentsPerPoll,
      [&](const SceneIntersector& intersector, CancelPoll& poll) {
        return PathTracer(scene, settings, intersector,
                          scene.frame_cache().get_or_build<Emitters>(
                              "emitters", cancel, [&] { return std::make_shared<const Emitters>(scene); }),
                          scene.frame_cache().get_or_build<MaterialBsdfs>(
                              "material bsdfs", cancel, [&] { return std::make_shared<const MaterialBsdfs>(scene); }),
                          poll);
      },
      [&](const PathTracer& tracer, int x, int y) {
        glm::vec3 sum(0.0f);
        float coverage = 0.0f;
        SampleVariance variance;
        const PixelSamples pixel(seed, pixel_index(settings, x, y));
        for (int s = range.begin; s < range.end; ++s) {
          const auto sample = static_cast<std::uint32_t>(s);
          // The camera rays are traced a packet at a time, each shaded in its turn here.
          if (camera_rays.used_up()) tracer.trace_camera_rays(camera_rays, camera_ray);
          const int lane = camera_rays.take();
          const PathTracer::Result r = tracer.trace(camera_rays.ray(lane), pixel, sample, camera_rays.hit(lane));
          if (tracer.stopped()) return false;  // r is a path cut short
          ++out.stats().samples;
          // A dropped sample adds 0 to the sum that is divided by all samples, so the variance
          // counts it as a 0 too.
          const bool valid = finite(r.radiance);
          // A finite sample is held to the one radiance bound of every engine (radiance_limit.h),
          // so that the sums below stay finite.
          const glm::vec3 radiance = valid ? limit_radiance(r.radiance) : glm::vec3(0.0f);
          if (!valid) ++out.stats().invalid_samples;  // counted, and never allowed into the pixel
          sum += radiance;
          if (out.aovs().variance) variance.add(radiance);
          coverage += r.hit ? 1.0f : 0.0f;
          // The first-hit AOVs are those of the buffer's first sample: global sample 0 in pass 0
          // (what the merged frame keeps), and each later pass's own first so that a pass's
          // buffer is a complete image by itself.
          if (s != range.begin || !r.hit) continue;
          if (out.aovs().depth) out.depth(x, y) = r.first_depth;
          if (out.aovs().normal) out.normal(x, y) = r.first_normal;
          if (out.aovs().albedo) out.albedo(x, y) = r.first_albedo;
        }
        const float inv = 1.0f / static_cast<float>(range.count());
        out.rgba(x, y) = glm::vec4(sum * inv, coverage * inv);
        if (out.aovs().variance) out.variance(x, y) = variance.of_mean();
        return true;
      });
}

}  // namespace farm::path
