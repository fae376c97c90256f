#pragma once
// Exact Fresnel reflectance of a smooth dielectric boundary for unpolarised light: the mean of
// the s- and p-polarised reflectances from the Fresnel equations.
#include <algorithm>
#include <cmath>

namespace farm {

// `cos_incident` is the cosine between the incoming direction (reversed) and the normal on the
// incident side, in [0, 1]; eta_i and eta_t are the refractive indices on the incident and the
// transmitted side. Returns 1 under total internal reflection.
inline float fresnel_dielectric(float cos_incident, float eta_i, float eta_t) {
  const float cos_i = std::clamp(cos_incident, 0.0f, 1.0f);
  const float sin_i = std::sqrt(std::max(0.0f, 1.0f - cos_i * cos_i));
  const float sin_t = eta_i / eta_t * sin_i;  // Snell's law
  if (sin_t >= 1.0f) return 1.0f;             // total internal reflection
  const float cos_t = std::sqrt(std::max(0.0f, 1.0f - sin_t * sin_t));
  const float r_s = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
  const float r_p = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
  return 0.5f * (r_s * r_s + r_p * r_p);
}

}  // namespace farm
