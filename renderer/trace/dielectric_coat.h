#pragma once
// A rough dielectric coat over a diffuse base, the dielectric half of glTF's metal-roughness
// material in the path tracer (docs/architecture.md, §8.2): what fraction of the light arriving
// at cos(theta) = mu passes the coat's GGX interface into the base (its transmittance T(mu)), and
// what fraction of the light the base sends up, spread diffusely, the interface reflects back down
// (its internal reflectance). The base then reflects kd * T(mu_o) T(mu_i) / (pi eta^2 (1 - R_int)):
// the light that enters, scattered diffusely and bounced between base and coat, leaves by T again
// and is spread over eta^2 the solid angle outside. For a white base the coat and base together
// reflect all the light the interface does not lose to masking, and the model is reciprocal: the
// layered plastic of Weidlich and Wilkie (2007), Mitsuba 3's roughplastic with nonlinear=false.
//
// Both come from tables over the roughness alpha and mu, integrated by quadrature over the visible
// normals for each index of refraction on a grid (1 to 3 in steps of 0.05) by the build
// (dielectric_coat_quadrature.h); an index between grid points interpolates the two beside it.

namespace farm {

class DielectricCoat {
 public:
  // `eta` the coat's index of refraction over the outside's (clamped to [1, 3]), `alpha` its
  // GGX roughness.
  DielectricCoat(float eta, float alpha);

  float eta() const { return eta_; }
  // Fraction of the light arriving from outside at cos(theta) = mu that reaches the base.
  float transmittance(float mu) const;
  // Fraction of diffuse light from the base that the interface reflects back to it.
  float internal_reflectance() const { return internal_reflectance_; }

 private:
  struct Row {
    const float* values = nullptr;  // transmittance over mu, one alpha of one eta's table
    float weight = 0.0f;
  };
  Row rows_[4];  // (eta below, above) x (alpha below, above); unused ones weigh 0
  float eta_ = 1.5f;
  float internal_reflectance_ = 0.0f;
};

}  // namespace farm
