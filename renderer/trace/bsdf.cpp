#include "renderer/trace/bsdf.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>

#include "renderer/trace/fresnel.h"
#include "renderer/trace/ggx.h"
#include "renderer/trace/sample_warp.h"
#include "renderer/util/pi.h"

namespace farm {
namespace {

float max_component(const glm::vec3& v) { return std::max({v.x, v.y, v.z}); }

// The GGX alpha from which glTF's glass is rough rather than smooth.
constexpr float kRoughGlassAlpha = 1e-3f;

// Rough glass is worked out with wo above the surface: a pair of directions with wo below is
// mirrored through the surface's plane, where the indices swap (an isotropic microfacet surface
// looks the same from below, mirrored). `eta`: the index below over the index above.
struct SeenFromAbove {
  glm::vec3 wo, wi;
  float eta;
};
SeenFromAbove seen_from_above(const glm::vec3& wo, const glm::vec3& wi, float ior) {
  if (wo.z >= 0.0f) return {wo, wi, ior};
  return {{wo.x, wo.y, -wo.z}, {wi.x, wi.y, -wi.z}, 1.0f / ior};
}

// The microfacet normal that turns wo into wi (wo above): their half vector for a reflection, the
// generalised one, -(wo + eta wi), for a refraction; on the upper side. None (z 0) where no
// facet facing both directions the right way does it.
glm::vec3 turning_normal(const SeenFromAbove& d) {
  const bool reflected = d.wi.z > 0.0f;
  glm::vec3 m = reflected ? d.wo + d.wi : d.wo + d.eta * d.wi;
  const float length = glm::length(m);
  if (!(length > 0.0f)) return glm::vec3(0.0f);
  m /= length;
  if (m.z < 0.0f) m = -m;
  // wo on the facet's front; wi on its front for a reflection, its back for a refraction.
  const float o = glm::dot(d.wo, m), i = glm::dot(d.wi, m);
  if (o <= 0.0f || (reflected ? i <= 0.0f : i >= 0.0f)) return glm::vec3(0.0f);
  return m;
}

}  // namespace

float Bsdf::roughness_from_shininess(float shininess) {
  return std::clamp(std::sqrt(2.0f / (std::max(shininess, 0.0f) + 2.0f)), 1e-3f, 1.0f);
}

// Out of line: inlined into callers whose material has no metal-roughness values, GCC 12 warns
// that the empty optional's metallic "may be used uninitialized" in transmitted_share.
Bsdf::Bsdf(const Material& m) : Bsdf(m, m.transmitted_share() > 0.0f) {}

Bsdf::Bsdf(const Material& m, bool transmitted) {
  if (transmitted) {
    kind_ = Kind::Dielectric;
    ior_ = m.ior;
    tint_ = m.transmission_tint();
    // glTF's glass is as rough as the rest of its surface; below alpha 1e-3 it is smooth for every
    // purpose (and Phong glass always is).
    if (m.metal_roughness && m.metal_roughness->roughness * m.metal_roughness->roughness >= kRoughGlassAlpha) {
      kind_ = Kind::RoughDielectric;
      alpha_ = std::min(m.metal_roughness->roughness * m.metal_roughness->roughness, 1.0f);
    }
    return;
  }
  if (const std::optional<MetalRoughness>& mr = m.metal_roughness) {
    kind_ = Kind::MetalRoughness;
    specular_ = glm::clamp(mr->base_colour, 0.0f, 1.0f);
    // Of what is not glass (1 - t (1 - metallic)), metallic is the metal's share.
    const float opaque = 1.0f - m.transmitted_share();
    metallic_ = opaque > 0.0f ? std::clamp(mr->metallic / opaque, 0.0f, 1.0f) : 0.0f;
    alpha_ = std::clamp(mr->roughness * mr->roughness, 1e-3f, 1.0f);
    coat_.emplace(m.ior, alpha_);
    const float eta = coat_->eta();
    diffuse_ = specular_ * ((1.0f - metallic_) / (kPi * eta * eta * (1.0f - coat_->internal_reflectance())));
    return;
  }
  if (m.is_mirror()) {
    kind_ = Kind::Mirror;
    specular_ = m.specular == glm::vec3(0.0f) ? glm::vec3(1.0f) : glm::min(m.specular, glm::vec3(1.0f));
    return;
  }
  // What the specular layer reflects is not available to the diffuse one below it.
  specular_ = glm::clamp(m.specular, 0.0f, 1.0f);
  diffuse_ = glm::clamp(m.diffuse, 0.0f, 1.0f) * (1.0f - max_component(specular_));
  if (specular_ == glm::vec3(0.0f)) return;  // Lambertian: no glossy layer, no roughness to work out
  kind_ = Kind::Layered;
  alpha_ = roughness_from_shininess(m.shininess);
  // ks is the glossy layer's albedo: single scattering reflects ks * E(mu) of it, and the
  // multiple-scattering lobe (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)) the rest, so the
  // layer reflects exactly ks at every angle and roughness.
  const float e_avg = ggx::average_albedo(alpha_);
  if (e_avg < 1.0f) multiple_scattering_ = specular_ / (kPi * (1.0f - e_avg));
  // VNDF sampling for the single-scattering part, the cosine lobe for diffuse and the rest.
  const float s = max_component(specular_), d = max_component(diffuse_);
  specular_probability_ = s + d > 0.0f ? s * e_avg / (s + d) : 0.0f;
}

glm::vec3 Bsdf::eval_layered(const glm::vec3& wo, const glm::vec3& wi) const {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return glm::vec3(0.0f);
  glm::vec3 f = diffuse_ * (1.0f / kPi);  // a product, not three divisions: every bounce pays it
  if (specular_ != glm::vec3(0.0f)) {
    const glm::vec3 m = glm::normalize(wo + wi);
    f += specular_ * (ggx::distribution(m, alpha_) * ggx::smith_g2(wo, wi, alpha_) / (4.0f * wo.z * wi.z));
    f += multiple_scattering_ *
         ((1.0f - ggx::directional_albedo(alpha_, wo.z)) * (1.0f - ggx::directional_albedo(alpha_, wi.z)));
  }
  return f;
}

// Schlick's Fresnel from the base colour for the metal, the exact dielectric one for the coat
// (whose F0 is 0.04 at glTF's ior 1.5), at the microfacet's cosine; the coat's diffuse base below.
glm::vec3 Bsdf::eval_metal_roughness(const glm::vec3& wo, const glm::vec3& wi) const {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return glm::vec3(0.0f);
  const glm::vec3 m = glm::normalize(wo + wi);
  const float cos_m = std::max(0.0f, glm::dot(wo, m));
  const float schlick = std::pow(1.0f - cos_m, 5.0f);
  const glm::vec3 fresnel = (1.0f - metallic_) * fresnel_dielectric(cos_m, 1.0f, coat_->eta()) +
                            metallic_ * (specular_ + (1.0f - specular_) * schlick);
  glm::vec3 f = fresnel * (ggx::distribution(m, alpha_) * ggx::smith_g2(wo, wi, alpha_) / (4.0f * wo.z * wi.z));
  if (metallic_ < 1.0f) f += diffuse_ * (coat_->transmittance(wo.z) * coat_->transmittance(wi.z));
  return f;
}

float Bsdf::metal_roughness_specular_probability(const glm::vec3& wo) const {
  // What each lobe reflects, roughly: the metal all of its light, the coat what it does not
  // let in; the base its colour of what the coat lets in.
  const float entering = coat_->transmittance(wo.z);
  const float s = metallic_ + (1.0f - metallic_) * (1.0f - entering);
  const float d = (1.0f - metallic_) * max_component(specular_) * entering;
  return s + d > 0.0f ? s / (s + d) : 1.0f;
}

// Walter et al. 2007: F D G / (4 |cos_o cos_i|) reflected; refracted, for radiance,
// (1 - F) D G |wi.m| |wo.m| / (|cos_o cos_i| (wo.m + eta wi.m)^2), which carries the (1 / eta)^2
// compression of radiance entering a denser medium, times the tint. The density: the visible
// normal's, times the Fresnel odds of the lobe taken, times the Jacobian from the normal to the
// direction it turns wo into.
Bsdf::Evaluated Bsdf::rough_dielectric(const glm::vec3& wo_any, const glm::vec3& wi_any) const {
  const SeenFromAbove d = seen_from_above(wo_any, wi_any, ior_);
  if (d.wo.z == 0.0f || d.wi.z == 0.0f) return {};
  const glm::vec3 m = turning_normal(d);
  if (m.z == 0.0f) return {};
  const float o = glm::dot(d.wo, m), i = glm::dot(d.wi, m);
  const float fresnel = fresnel_dielectric(o, 1.0f, d.eta);
  const float dg = ggx::distribution(m, alpha_) * ggx::smith_g2(d.wo, d.wi, alpha_);
  const float cosines = d.wo.z * std::fabs(d.wi.z);
  const float visible = ggx::visible_normal_pdf(d.wo, m, alpha_);
  if (d.wi.z > 0.0f) return {glm::vec3(fresnel * dg / (4.0f * cosines)), fresnel * visible / (4.0f * o)};
  const float spread = o + d.eta * i;
  return {tint_ * ((1.0f - fresnel) * dg * std::fabs(i) * o / (cosines * spread * spread)),
          (1.0f - fresnel) * visible * d.eta * d.eta * std::fabs(i) / (spread * spread)};
}

std::optional<BsdfSample> Bsdf::sample_rough_dielectric(const glm::vec3& wo_any, float u_lobe, float u1,
                                                       float u2) const {
  const bool below = wo_any.z < 0.0f;
  const SeenFromAbove d = seen_from_above(wo_any, glm::vec3(0.0f), ior_);
  if (d.wo.z == 0.0f) return std::nullopt;
  const glm::vec3 m = ggx::sample_visible_normal(d.wo, alpha_, u1, u2);
  const float o = glm::dot(d.wo, m);
  if (!(o > 0.0f)) return std::nullopt;
  glm::vec3 wi;
  if (u_lobe < fresnel_dielectric(o, 1.0f, d.eta)) {
    wi = ggx::reflect_about(d.wo, m);
    if (wi.z <= 0.0f) return std::nullopt;  // reflected into the surface: lost
  } else {
    // Snell's law about the facet, from the index above (1) into the one below (eta).
    const float sin2_t = (1.0f - o * o) / (d.eta * d.eta);
    if (sin2_t >= 1.0f) return std::nullopt;  // total internal reflection: Fresnel took this branch
    wi = glm::normalize(-d.wo / d.eta + (o / d.eta - std::sqrt(1.0f - sin2_t)) * m);
    if (wi.z >= 0.0f) return std::nullopt;  // refracted back out above: lost
  }
  if (below) wi.z = -wi.z;
  const Evaluated e = rough_dielectric(wo_any, wi);
  if (!(e.pdf > 0.0f)) return std::nullopt;
  BsdfSample s;
  s.wi = wi;
  s.pdf = e.pdf;
  s.weight = e.f * std::fabs(wi.z) / e.pdf;
  return s;
}

float Bsdf::mixture_pdf(const glm::vec3& wo, const glm::vec3& wi, float specular_probability) const {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
  float pdf = (1.0f - specular_probability) * wi.z / kPi;
  if (specular_probability > 0.0f) {
    const glm::vec3 m = glm::normalize(wo + wi);
    pdf += specular_probability * ggx::visible_normal_pdf(wo, m, alpha_) / (4.0f * glm::dot(wo, m));
  }
  return pdf;
}

template <typename Eval>
std::optional<BsdfSample> Bsdf::sample_mixture(const glm::vec3& wo, float u_lobe, float u1, float u2,
                                               float specular_probability, Eval&& eval) const {
  if (wo.z <= 0.0f) return std::nullopt;
  BsdfSample s;
  if (u_lobe < specular_probability) {
    s.wi = ggx::reflect_about(wo, ggx::sample_visible_normal(wo, alpha_, u1, u2));
  } else {
    s.wi = cosine_hemisphere(u1, u2);
  }
  if (s.wi.z <= 0.0f) return std::nullopt;
  s.pdf = mixture_pdf(wo, s.wi, specular_probability);
  if (!(s.pdf > 0.0f)) return std::nullopt;
  s.weight = eval(wo, s.wi) * s.wi.z / s.pdf;
  return s;
}

glm::vec3 Bsdf::eval_other(const glm::vec3& wo, const glm::vec3& wi) const {
  switch (kind_) {
    case Kind::Lambertian:  // eval_layered without the glossy layer: the same bits
    case Kind::Layered: return eval_layered(wo, wi);
    case Kind::MetalRoughness: return eval_metal_roughness(wo, wi);
    case Kind::RoughDielectric: return rough_dielectric(wo, wi).f;
    default: return glm::vec3(0.0f);
  }
}

float Bsdf::pdf_other(const glm::vec3& wo, const glm::vec3& wi) const {
  switch (kind_) {
    case Kind::Lambertian:  // specular_probability_ is 0
    case Kind::Layered: return mixture_pdf(wo, wi, specular_probability_);
    case Kind::MetalRoughness: return mixture_pdf(wo, wi, metal_roughness_specular_probability(wo));
    case Kind::RoughDielectric: return rough_dielectric(wo, wi).pdf;
    default: return 0.0f;
  }
}

bool Bsdf::sample_other(const glm::vec3& wo, float u_lobe, float u1, float u2, BsdfSample& s) const {
  // The lobes sampled out of line, whose samples come back as optionals.
  const auto taken = [&s](const std::optional<BsdfSample>& sample) {
    if (sample) s = *sample;
    return sample.has_value();
  };
  switch (kind_) {
    case Kind::Mirror:
      if (wo.z <= 0.0f) return false;
      s.wi = {-wo.x, -wo.y, wo.z};
      s.weight = specular_;
      s.pdf = 1.0f;
      s.specular = true;
      return true;

    case Kind::Dielectric: {
      // Indices on the side wo is on, and on the other side; the normal flipped to wo's side.
      const bool entering = wo.z > 0.0f;
      const float eta_i = entering ? 1.0f : ior_, eta_t = entering ? ior_ : 1.0f;
      const glm::vec3 n{0.0f, 0.0f, entering ? 1.0f : -1.0f};
      const float cos_i = std::fabs(wo.z);
      const float reflectance = fresnel_dielectric(cos_i, eta_i, eta_t);
      s.specular = true;
      if (u_lobe < reflectance) {
        s.wi = {-wo.x, -wo.y, wo.z};
        s.weight = glm::vec3(1.0f);
        s.pdf = reflectance;
        return true;
      }
      const float eta = eta_i / eta_t;
      const float cos_t = std::sqrt(std::max(0.0f, 1.0f - eta * eta * (1.0f - cos_i * cos_i)));
      s.wi = glm::normalize(-eta * wo + (eta * cos_i - cos_t) * n);
      // Radiance is compressed by (eta_i / eta_t)^2 entering a denser medium (it cancels on the
      // way back out).
      s.weight = eta * eta * tint_;
      s.pdf = 1.0f - reflectance;
      return true;
    }

    case Kind::RoughDielectric: return taken(sample_rough_dielectric(wo, u_lobe, u1, u2));

    case Kind::Lambertian: return sample_lambertian(wo, u1, u2, s);
    case Kind::Layered:
      return taken(sample_mixture(wo, u_lobe, u1, u2, specular_probability_,
                                  [this](const glm::vec3& o, const glm::vec3& i) { return eval_layered(o, i); }));
    case Kind::MetalRoughness:
      return taken(sample_mixture(wo, u_lobe, u1, u2, metal_roughness_specular_probability(wo),
                                  [this](const glm::vec3& o, const glm::vec3& i) { return eval_metal_roughness(o, i); }));
  }
  return false;
}

}  // namespace farm
