#pragma once
// Scattering functions for the path tracer, mapped from the Phong material (docs/architecture.md, "Conventions"):
//   smooth dielectric  the glass part of a material (Material::transmitted_share: Fresnel
//                      reflection and refraction, tinted by transmission_tint at each crossing);
//                      a partly transmissive material is this part or the rest, picked per hit
//   rough dielectric   that glass part of a glTF material whose roughness is above about 0.03:
//                      GGX microfacets of alpha roughness^2, each a smooth boundary of the ior,
//                      reflecting and refracting (Walter et al. 2007), visible normals sampled
//   metal-roughness    glTF's materials (Material::metal_roughness): GGX of alpha roughness^2
//                      with Schlick's Fresnel from the base colour, weighed by metallic, over a
//                      diffuse base under a rough dielectric coat of index ior (DielectricCoat),
//                      weighed by 1 - metallic; single scattering, as glTF's reference and Mitsuba
//                      (a blend of roughplastic and principled) have it
//   perfect mirror     shininess >= 1000 (reflectance ks, or white when ks is black)
//   diffuse + glossy   (1 - max ks) * Lambert(kd) + ks * GGX, roughness from the shininess, with
//                      the energy single scattering loses given back (multiple scattering)
// All are energy conserving. Directions live in the local shading frame: z is the normal, and
// wo (towards the viewer) and wi (towards the light) both point away from the surface.
#include <glm/vec3.hpp>
#include <optional>

#include "renderer/scene/material.h"
#include "renderer/trace/dielectric_coat.h"
#include "renderer/trace/sample_warp.h"
#include "renderer/util/pi.h"

namespace farm {

struct BsdfSample {
  glm::vec3 wi{0.0f};
  glm::vec3 weight{0.0f};  // f * |cos(wi)| / pdf: what the path throughput is multiplied by
  float pdf = 0.0f;        // solid-angle density; for delta lobes the discrete probability
  bool specular = false;   // a delta lobe: eval() and pdf() never see this direction
};

class Bsdf {
 public:
  // The BSDF of `material`'s glass part when `transmitted`, else of the rest (for glTF, its
  // metallic renormalised over what is left). A path picks the glass part with probability
  // transmitted_share(), so that on average it sees the whole.
  Bsdf(const Material& material, bool transmitted);
  // A material that is wholly one or the other; a partly transmissive one gets its glass part.
  explicit Bsdf(const Material& material);

  // The three below take a Lambertian surface (the commonest: every wall of a Cornell box) inline,
  // and the other kinds out of line: the calls, their switch and the returned structures through
  // memory were 7.6% of the Cornell box's instructions for a few multiplies (docs/architecture.md 8.1).

  // f(wo, wi) of the non-delta lobes (without the cosine).
  glm::vec3 eval(const glm::vec3& wo, const glm::vec3& wi) const {
    if (kind_ != Kind::Lambertian) return eval_other(wo, wi);
    if (wo.z <= 0.0f || wi.z <= 0.0f) return glm::vec3(0.0f);
    return diffuse_ * (1.0f / kPi);  // a product, not three divisions: every bounce pays it
  }
  // Density with which sample() picks wi given wo, non-delta lobes only.
  float pdf(const glm::vec3& wo, const glm::vec3& wi) const {
    if (kind_ != Kind::Lambertian) return pdf_other(wo, wi);
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    return wi.z / kPi;
  }
  // Picks wi for uniform numbers u_lobe, u1, u2 in [0, 1) into `s`; false when the sample is
  // lost (a glossy reflection that points below the surface), `s` then unspecified. The
  // integrator's form: as an optional, the inline Lambertian sample was stored in pieces and
  // reloaded as 16-byte words, which x86 CPUs do not forward from smaller stores
  // (docs/architecture.md 8.1: 12% of the integrator's samples waited there).
  bool sample(const glm::vec3& wo, float u_lobe, float u1, float u2, BsdfSample& s) const {
    return kind_ == Kind::Lambertian ? sample_lambertian(wo, u1, u2, s) : sample_other(wo, u_lobe, u1, u2, s);
  }
  std::optional<BsdfSample> sample(const glm::vec3& wo, float u_lobe, float u1, float u2) const {
    BsdfSample s;
    if (!sample(wo, u_lobe, u1, u2, s)) return std::nullopt;
    return s;
  }

  // Only delta lobes: next-event estimation has nothing to add here.
  bool is_specular() const { return kind_ == Kind::Mirror || kind_ == Kind::Dielectric; }

  // Blinn-Phong exponent -> GGX roughness alpha, through Beckmann's sqrt(2 / (p + 2)).
  static float roughness_from_shininess(float shininess);

 private:
  // Lambertian: a Layered material without its glossy layer, which samples its own lobe exactly
  // (weight kd, no evaluation: f cos / pdf is kd).
  enum class Kind { Lambertian, Layered, MetalRoughness, Mirror, Dielectric, RoughDielectric };

  // The cosine lobe is a Lambertian BSDF's exactly: f cos / pdf = (kd / pi) cos / (cos / pi) = kd,
  // not worked out (an evaluation and three divisions a bounce).
  bool sample_lambertian(const glm::vec3& wo, float u1, float u2, BsdfSample& s) const {
    if (wo.z <= 0.0f) return false;
    s.wi = cosine_hemisphere(u1, u2);
    if (!(s.wi.z > 0.0f)) return false;
    s.pdf = s.wi.z / kPi;
    s.weight = diffuse_;
    s.specular = false;
    return true;
  }
  // eval, pdf and sample out of line, for every kind (sample() and the others take Lambertian
  // inline).
  glm::vec3 eval_other(const glm::vec3& wo, const glm::vec3& wi) const;
  float pdf_other(const glm::vec3& wo, const glm::vec3& wi) const;
  bool sample_other(const glm::vec3& wo, float u_lobe, float u1, float u2, BsdfSample& s) const;

  glm::vec3 eval_layered(const glm::vec3& wo, const glm::vec3& wi) const;
  glm::vec3 eval_metal_roughness(const glm::vec3& wo, const glm::vec3& wi) const;
  // MetalRoughness: the chance of sampling GGX's visible normals rather than the cosine lobe,
  // seen from wo (Layered's is the constant specular_probability_).
  float metal_roughness_specular_probability(const glm::vec3& wo) const;
  // RoughDielectric, from either side of the surface: f and the density of sampling wi, worked
  // out together (they share the facet, its Fresnel and its distribution); zero for a pair no
  // facet joins.
  struct Evaluated {
    glm::vec3 f{0.0f};
    float pdf = 0.0f;
  };
  Evaluated rough_dielectric(const glm::vec3& wo, const glm::vec3& wi) const;
  std::optional<BsdfSample> sample_rough_dielectric(const glm::vec3& wo, float u_lobe, float u1, float u2) const;
  // Density of that mixture of the two sampling strategies, and a direction drawn from it
  // weighted by `eval`.
  float mixture_pdf(const glm::vec3& wo, const glm::vec3& wi, float specular_probability) const;
  template <typename Eval>
  std::optional<BsdfSample> sample_mixture(const glm::vec3& wo, float u_lobe, float u1, float u2,
                                           float specular_probability, Eval&& eval) const;

  Kind kind_ = Kind::Lambertian;
  glm::vec3 diffuse_{0.0f};   // kd scaled by what the specular layer leaves
  glm::vec3 specular_{0.0f};  // ks, or the mirror's reflectance
  glm::vec3 multiple_scattering_{0.0f};  // ks / (pi (1 - E_avg))
  float alpha_ = 1.0f;        // GGX roughness
  float ior_ = 1.5f;
  glm::vec3 tint_{1.0f};      // Dielectric, RoughDielectric: what refraction keeps
  float specular_probability_ = 0.0f;  // Layered: chance of sampling GGX visible normals
  // MetalRoughness: the base colour as ks above, metallic, and the coat with its diffuse base
  // (kd / (pi eta^2 (1 - R_int)) in diffuse_).
  float metallic_ = 0.0f;
  std::optional<DielectricCoat> coat_;
};

}  // namespace farm
