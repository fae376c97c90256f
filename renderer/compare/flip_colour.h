#pragma once
// FLIP's per-pixel colour science, inline so that the row loops vectorise: linear sRGB to the
// opponent space the CSF filters work in, and from filtered opponent values to the perceived
// colour difference (CIELAB with the Hunt effect, HyAB distance, remapped to [0, 1]); and the
// edge/point feature difference. Internal to renderer/compare.
#include <algorithm>
#include <cmath>

#include "renderer/compare/flip_math.h"

namespace farm::flip_detail {

struct Matrix3 {
  double m[3][3];
};

constexpr Matrix3 inverse(const Matrix3& a) {
  const auto& m = a.m;
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  Matrix3 r{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // The cofactor of m[j][i] over the determinant.
      const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      r.m[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
    }
  }
  return r;
}

// Linear sRGB to CIE XYZ, derived from the sRGB primaries and the D65 white point
// (x, y) = (0.31271, 0.32902): the matrix FLIP's references use, to double precision.
constexpr Matrix3 srgb_to_xyz() {
  const double primaries[3][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}};
  const double wx = 0.31271, wy = 0.32902;
  Matrix3 p{};  // columns: the XYZ of each primary at Y = 1
  for (int c = 0; c < 3; ++c) {
    const double x = primaries[c][0], y = primaries[c][1];
    p.m[0][c] = x / y;
    p.m[1][c] = 1.0;
    p.m[2][c] = (1.0 - x - y) / y;
  }
  // Scale each primary so that R = G = B = 1 is the white point.
  const Matrix3 inv = inverse(p);
  const double white[3] = {wx / wy, 1.0, (1.0 - wx - wy) / wy};
  Matrix3 m{};
  for (int c = 0; c < 3; ++c) {
    const double scale = inv.m[c][0] * white[0] + inv.m[c][1] * white[1] + inv.m[c][2] * white[2];
    for (int r = 0; r < 3; ++r) m.m[r][c] = p.m[r][c] * scale;
  }
  return m;
}

// XYZ divided by the white point's XYZ (the white of linear RGB (1, 1, 1)), which is what both
// YCxCz and CIELAB are built on.
constexpr Matrix3 srgb_to_relative_xyz() {
  Matrix3 m = srgb_to_xyz();
  for (int r = 0; r < 3; ++r) {
    const double white = m.m[r][0] + m.m[r][1] + m.m[r][2];
    for (int c = 0; c < 3; ++c) m.m[r][c] /= white;
  }
  return m;
}

// The opponent channels, kept in relative units: lum = Y/Yw, cx = X/Xw - Y/Yw, cz = Y/Yw - Z/Zw.
// YCxCz proper is (116 lum - 16, 500 cx, 200 cz); the CSF filters are linear and sum to one,
// so filtering these and scaling afterwards is the same thing. lum is also the normalised
// achromatic channel, (Y + 16) / 116, that the feature filters see.
struct Opponent {
  float lum, cx, cz;
};

// A matrix rounded to float once, for the per-pixel code: row r applied to (a, b, c).
struct FloatMatrix3 {
  float m[3][3];
  constexpr explicit FloatMatrix3(const Matrix3& d) : m{} {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m[r][c] = static_cast<float>(d.m[r][c]);
  }
  float row(int r, float a, float b, float c) const { return m[r][0] * a + m[r][1] * b + m[r][2] * c; }
};

inline constexpr Matrix3 kRelativeXyz = srgb_to_relative_xyz();
inline constexpr FloatMatrix3 kRelativeXyzF{kRelativeXyz};

inline Opponent to_opponent(float r, float g, float b) {
  const float x = kRelativeXyzF.row(0, r, g, b), y = kRelativeXyzF.row(1, r, g, b), z = kRelativeXyzF.row(2, r, g, b);
  return {y, x - y, y - z};
}

// Opponent (lum, cx, cz) back to linear RGB: relative XYZ is (lum + cx, lum, lum - cz).
constexpr Matrix3 opponent_to_srgb() {
  const Matrix3 to_rgb = inverse(kRelativeXyz);
  Matrix3 m{};
  for (int r = 0; r < 3; ++r) {
    m.m[r][0] = to_rgb.m[r][0] + to_rgb.m[r][1] + to_rgb.m[r][2];
    m.m[r][1] = to_rgb.m[r][0];
    m.m[r][2] = -to_rgb.m[r][2];
  }
  return m;
}

// The constants of the FLIP paper's colour pipeline: the exponent qc applied to
// the HyAB distance, and the remapping that sends [0, pc cmax) to [0, pt) and the rest to [pt, 1].
constexpr float kQc = 0.7f, kPc = 0.4f, kPt = 0.95f;

struct HuntLab {
  float l, a, b;
};

// Clamps to [0, 1], sending NaN (an infinite HDR value after tone mapping) to 0.
inline float clamp01(float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; }

// CIELAB's f(t): a cube root, and a line near black.
inline float lab_f(float t) {
  constexpr float delta = 6.0f / 29.0f, delta3 = delta * delta * delta;
  const float root = fast_cbrt(std::max(t, delta3));
  return t > delta3 ? root : t * (1.0f / (3.0f * delta * delta)) + 4.0f / 29.0f;
}

// Linear RGB (clamped to [0, 1]) to CIELAB, with the chroma scaled by 0.01 L (Hunt effect:
// colours look less saturated when dark).
inline HuntLab hunt_lab(float r, float g, float b) {
  r = clamp01(r);
  g = clamp01(g);
  b = clamp01(b);
  const float fx = lab_f(kRelativeXyzF.row(0, r, g, b));
  const float fy = lab_f(kRelativeXyzF.row(1, r, g, b));
  const float fz = lab_f(kRelativeXyzF.row(2, r, g, b));
  const float l = 116.0f * fy - 16.0f;
  return {l, 0.01f * l * 500.0f * (fx - fy), 0.01f * l * 200.0f * (fy - fz)};
}

// HyAB: city-block in lightness, Euclidean in chroma.
inline float hyab(const HuntLab& p, const HuntLab& q) {
  const float da = p.a - q.a, db = p.b - q.b;
  return std::abs(p.l - q.l) + std::sqrt(da * da + db * db);
}

inline HuntLab opponent_to_hunt_lab(float lum, float cx, float cz) {
  constexpr FloatMatrix3 m{opponent_to_srgb()};
  return hunt_lab(m.row(0, lum, cx, cz), m.row(1, lum, cx, cz), m.row(2, lum, cx, cz));
}

// The remapping of HyAB^qc to [0, 1], from cmax: the distance between the two colours of the
// gamut furthest apart, green and blue.
struct ColourRemap {
  float pccmax, low_scale, high_scale;

  static ColourRemap make() {
    const float cmax = std::pow(hyab(hunt_lab(0.0f, 1.0f, 0.0f), hunt_lab(0.0f, 0.0f, 1.0f)), kQc);
    const float pccmax = kPc * cmax;
    return {pccmax, kPt / pccmax, (1.0f - kPt) / (cmax - pccmax)};
  }
};

// The colour error in [0, 1] of two filtered opponent values.
inline float colour_difference(const ColourRemap& k, float lum1, float cx1, float cz1, float lum2, float cx2,
                               float cz2) {
  const float d = fast_pow(hyab(opponent_to_hunt_lab(lum1, cx1, cz1), opponent_to_hunt_lab(lum2, cx2, cz2)), kQc);
  return d < k.pccmax ? d * k.low_scale : kPt + (d - k.pccmax) * k.high_scale;
}

// The feature difference in [0, 1]: the larger change in edge or point strength (gradient
// magnitudes of the first and second derivative filters), over sqrt(2), to the power qf = 1/2.
inline float feature_difference(float dx1, float dy1, float dxx1, float dyy1, float dx2, float dy2, float dxx2,
                                float dyy2) {
  const float edge = std::abs(std::sqrt(dx1 * dx1 + dy1 * dy1) - std::sqrt(dx2 * dx2 + dy2 * dy2));
  const float point = std::abs(std::sqrt(dxx1 * dxx1 + dyy1 * dyy1) - std::sqrt(dxx2 * dxx2 + dyy2 * dyy2));
  return std::sqrt(std::max(edge, point) * 0.70710678f);
}

}  // namespace farm::flip_detail
