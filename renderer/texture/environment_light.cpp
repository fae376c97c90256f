#include "renderer/texture/environment_light.h"
#include "renderer/util/pi.h"
#include "renderer/util/unit_circle.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>
#include <stdexcept>
#include <utility>


namespace farm {
namespace {

// The sampling distribution and the harmonics read a level of the map at most this large: a
// larger map's 2x2 averages shape where samples go just as well, and its memory stays bounded
// (two floats a texel: 16 MiB).
constexpr std::int64_t kMaxDistributionTexels = std::int64_t{1} << 21;
constexpr int kMaxHarmonicsWidth = 512;

float luminance(const glm::vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

bool finite_non_negative(float x) { return std::isfinite(x) && x >= 0.0f; }

// The map's (u, v) of a unit direction in its frame, and back.
glm::vec2 uv_of(const glm::vec3& d) {
  float u = std::atan2(d.x, -d.z) * (0.5f / kPi);
  if (u < 0.0f) u += 1.0f;
  const float v = std::acos(std::clamp(d.y, -1.0f, 1.0f)) / kPi;
  return {u, v};
}
glm::vec3 direction_of(float u, float v) {
  const float phi = 2.0f * kPi * u, theta = kPi * v;
  const float sin_theta = std::sin(theta);
  return {sin_theta * std::sin(phi), std::cos(theta), -sin_theta * std::cos(phi)};
}

// The first level of `map` at most `fits` allows.
template <typename Fits>
int first_level_that(const Texture& map, Fits&& fits) {
  int level = 0;
  while (level + 1 < map.levels() && !fits(map.level_width(level), map.level_height(level))) ++level;
  return level;
}

// Index of the interval of the running sums `cdf` (n + 1 entries, 0 to 1) that holds u.
int interval_of(const float* cdf, int n, float u) {
  const float* found = std::upper_bound(cdf, cdf + n + 1, u);
  return std::clamp(static_cast<int>(found - cdf) - 1, 0, n - 1);
}

// The nine real spherical harmonics at a unit direction.
void harmonics(const glm::vec3& d, float y[9]) {
  y[0] = 0.282095f;
  y[1] = 0.488603f * d.y;
  y[2] = 0.488603f * d.z;
  y[3] = 0.488603f * d.x;
  y[4] = 1.092548f * d.x * d.y;
  y[5] = 1.092548f * d.y * d.z;
  y[6] = 0.315392f * (3.0f * d.z * d.z - 1.0f);
  y[7] = 1.092548f * d.x * d.z;
  y[8] = 0.546274f * (d.x * d.x - d.y * d.y);
}

}  // namespace

EnvironmentLight::EnvironmentLight(glm::vec3 radiance, float intensity, float rotation_degrees,
                                   std::shared_ptr<const Texture> map)
    : map_(std::move(map)) {
  if (!finite_non_negative(radiance.x) || !finite_non_negative(radiance.y) || !finite_non_negative(radiance.z) ||
      !finite_non_negative(intensity) || !std::isfinite(rotation_degrees)) {
    throw std::invalid_argument("EnvironmentLight: radiance and intensity must be finite and not negative");
  }
  scale_ = radiance * intensity;
  const float angle = rotation_degrees * (kPi / 180.0f);
  cos_rotation_ = std::cos(angle);
  sin_rotation_ = std::sin(angle);
  // Around the sphere u wraps; over the poles v stops at the edge rows. Level 0 only: a ray
  // leaving the scene has no footprint to pick a coarser level by.
  sampler_.wrap_u = TextureWrap::Repeat;
  sampler_.wrap_v = TextureWrap::ClampToEdge;
  sampler_.mipmaps = false;
  if (map_) {
    build_distribution();
    project_irradiance();
  }
}

// A turn by the rotation about +y (right-handed), and its inverse.
glm::vec3 EnvironmentLight::to_world(const glm::vec3& m) const {
  return {cos_rotation_ * m.x + sin_rotation_ * m.z, m.y, -sin_rotation_ * m.x + cos_rotation_ * m.z};
}
glm::vec3 EnvironmentLight::to_map(const glm::vec3& w) const {
  return {cos_rotation_ * w.x - sin_rotation_ * w.z, w.y, sin_rotation_ * w.x + cos_rotation_ * w.z};
}

glm::vec3 EnvironmentLight::radiance(const glm::vec3& direction) const {
  if (!map_) return scale_;
  const float length = glm::length(direction);
  if (!(length > 0.0f) || !std::isfinite(length)) return glm::vec3(0.0f);
  return scale_ * glm::vec3(map_->sample(uv_of(to_map(direction / length)), sampler_));
}

void EnvironmentLight::build_distribution() {
  level_ = first_level_that(*map_, [](int w, int h) { return std::int64_t{w} * h <= kMaxDistributionTexels; });
  columns_ = map_->level_width(level_);
  rows_ = map_->level_height(level_);
  weight_.resize(static_cast<std::size_t>(rows_) * static_cast<std::size_t>(columns_));
  column_cdf_.resize(static_cast<std::size_t>(rows_) * static_cast<std::size_t>(columns_ + 1));
  row_cdf_.assign(static_cast<std::size_t>(rows_) + 1, 0.0f);
  std::vector<double> row_total(static_cast<std::size_t>(rows_), 0.0);
  double total = 0.0;
  for (int y = 0; y < rows_; ++y) {
    const float sin_theta = std::sin(kPi * (static_cast<float>(y) + 0.5f) / static_cast<float>(rows_));
    float* cdf = &column_cdf_[static_cast<std::size_t>(y) * static_cast<std::size_t>(columns_ + 1)];
    double sum = 0.0;
    cdf[0] = 0.0f;
    for (int x = 0; x < columns_; ++x) {
      const float lum = luminance(scale_ * glm::vec3(map_->texel(level_, x, y)));
      // A texel that is negative or not finite is dark to the sampler (its value still shows).
      const float w = std::isfinite(lum) && lum > 0.0f ? lum * sin_theta : 0.0f;
      weight_[static_cast<std::size_t>(y) * static_cast<std::size_t>(columns_) + static_cast<std::size_t>(x)] = w;
      sum += w;
      cdf[x + 1] = static_cast<float>(sum);
    }
    // A dark row is never picked; its columns are spread evenly so that the sums stay ordered.
    for (int x = 1; x <= columns_; ++x) {
      cdf[x] = sum > 0.0 ? static_cast<float>(cdf[x] / sum) : static_cast<float>(x) / static_cast<float>(columns_);
    }
    cdf[columns_] = 1.0f;
    row_total[static_cast<std::size_t>(y)] = sum;
    total += sum;
  }
  weight_mean_ = total / (static_cast<double>(rows_) * static_cast<double>(columns_));
  double running = 0.0;
  for (int y = 0; y < rows_; ++y) {
    running += row_total[static_cast<std::size_t>(y)];
    row_cdf_[static_cast<std::size_t>(y) + 1] = total > 0.0 ? static_cast<float>(running / total) : 0.0f;
  }
  if (total > 0.0) row_cdf_[static_cast<std::size_t>(rows_)] = 1.0f;
}

std::optional<EnvironmentLight::Sample> EnvironmentLight::sample(float u1, float u2) const {
  Sample s;
  if (!map_) {
    if (scale_ == glm::vec3(0.0f)) return std::nullopt;
    // Uniform over the sphere.
    const float z = 1.0f - 2.0f * u1;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const CosSin phi = unit_circle_point(u2);
    s.direction = {r * phi.cos, r * phi.sin, z};
    s.radiance = scale_;
    s.pdf = 1.0f / (4.0f * kPi);
    return s;
  }
  if (!(weight_mean_ > 0.0)) return std::nullopt;
  const int y = interval_of(row_cdf_.data(), rows_, u1);
  const float* cdf = &column_cdf_[static_cast<std::size_t>(y) * static_cast<std::size_t>(columns_ + 1)];
  const int x = interval_of(cdf, columns_, u2);
  // Where in the texel: the numbers' place within the chosen intervals, uniform again.
  const float row_width = row_cdf_[static_cast<std::size_t>(y) + 1] - row_cdf_[static_cast<std::size_t>(y)];
  const float column_width = cdf[x + 1] - cdf[x];
  const float dv = row_width > 0.0f ? std::clamp((u1 - row_cdf_[static_cast<std::size_t>(y)]) / row_width, 0.0f, 1.0f) : 0.5f;
  const float du = column_width > 0.0f ? std::clamp((u2 - cdf[x]) / column_width, 0.0f, 1.0f) : 0.5f;
  const float u = (static_cast<float>(x) + du) / static_cast<float>(columns_);
  const float v = (static_cast<float>(y) + dv) / static_cast<float>(rows_);
  const float sin_theta = std::sin(kPi * v);
  if (!(sin_theta > 0.0f)) return std::nullopt;
  const float w = weight_[static_cast<std::size_t>(y) * static_cast<std::size_t>(columns_) + static_cast<std::size_t>(x)];
  s.pdf = static_cast<float>(w / weight_mean_) / (2.0f * kPi * kPi * sin_theta);
  if (!(s.pdf > 0.0f) || !std::isfinite(s.pdf)) return std::nullopt;
  s.direction = to_world(direction_of(u, v));
  s.radiance = scale_ * glm::vec3(map_->sample({u, v}, sampler_));
  return s;
}

float EnvironmentLight::pdf(const glm::vec3& direction) const {
  if (!map_) return scale_ == glm::vec3(0.0f) ? 0.0f : 1.0f / (4.0f * kPi);
  if (!(weight_mean_ > 0.0)) return 0.0f;
  const glm::vec3 d = to_map(direction);
  const glm::vec2 uv = uv_of(d);
  const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - d.y * d.y));
  if (!(sin_theta > 0.0f)) return 0.0f;
  const int x = std::clamp(static_cast<int>(uv.x * static_cast<float>(columns_)), 0, columns_ - 1);
  const int y = std::clamp(static_cast<int>(uv.y * static_cast<float>(rows_)), 0, rows_ - 1);
  const float w = weight_[static_cast<std::size_t>(y) * static_cast<std::size_t>(columns_) + static_cast<std::size_t>(x)];
  return static_cast<float>(w / weight_mean_) / (2.0f * kPi * kPi * sin_theta);
}

void EnvironmentLight::project_irradiance() {
  // Radiance projected on the harmonics by summing the texels of a small level, each weighted by
  // its solid angle; the sum of those angles is scaled to 4 pi exactly, so that a map of one
  // value gives that value's irradiance.
  const int level = first_level_that(*map_, [](int w, int) { return w <= kMaxHarmonicsWidth; });
  const int w = map_->level_width(level), h = map_->level_height(level);
  glm::dvec3 coefficients[9]{};
  double solid_angle = 0.0;
  for (int y = 0; y < h; ++y) {
    const float v = (static_cast<float>(y) + 0.5f) / static_cast<float>(h);
    const double d_omega = (2.0 * std::numbers::pi / w) * (std::numbers::pi / h) * std::sin(std::numbers::pi * v);
    for (int x = 0; x < w; ++x) {
      const glm::vec3 texel(map_->texel(level, x, y));
      if (!std::isfinite(texel.x) || !std::isfinite(texel.y) || !std::isfinite(texel.z)) continue;
      float basis[9];
      harmonics(direction_of((static_cast<float>(x) + 0.5f) / static_cast<float>(w), v), basis);
      for (int i = 0; i < 9; ++i) coefficients[i] += glm::dvec3(texel) * static_cast<double>(basis[i]) * d_omega;
      solid_angle += d_omega;
    }
  }
  // The cosine lobe's convolution: pi for band 0, 2 pi / 3 for band 1, pi / 4 for band 2.
  const double band[9] = {std::numbers::pi,       2.0 * std::numbers::pi / 3.0, 2.0 * std::numbers::pi / 3.0,
                          2.0 * std::numbers::pi / 3.0, std::numbers::pi / 4.0, std::numbers::pi / 4.0,
                          std::numbers::pi / 4.0, std::numbers::pi / 4.0,       std::numbers::pi / 4.0};
  const double normalise = solid_angle > 0.0 ? 4.0 * std::numbers::pi / solid_angle : 0.0;
  for (int i = 0; i < 9; ++i) sh_[i] = glm::vec3(coefficients[i] * band[i] * normalise) * scale_;
}

glm::vec3 EnvironmentLight::irradiance(const glm::vec3& normal) const {
  if (!map_) return kPi * scale_;
  float basis[9];
  harmonics(to_map(normal), basis);
  glm::vec3 e(0.0f);
  for (int i = 0; i < 9; ++i) e += sh_[i] * basis[i];
  // Nine harmonics ring below zero opposite a small bright source: no light is negative.
  return glm::max(e, glm::vec3(0.0f));
}

}  // namespace farm
