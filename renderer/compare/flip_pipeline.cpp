#include "renderer/compare/flip_pipeline.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <numbers>

#include "renderer/compare/flip_colour.h"
#include "renderer/util/thread_pool.h"

namespace farm::flip_detail {
namespace {

// Contrast sensitivity in the frequency domain is modelled per opponent channel as a sum of
// Gaussians a exp(-b f^2); its spatial counterpart is a sqrt(pi/b) exp(-pi^2 x^2 / b), x in
// degrees (the FLIP paper's colour pipeline). Blue-yellow needs two terms, the others one.
struct CsfTerm {
  double a, b;
};
constexpr CsfTerm kCsfY{1.0, 0.0047};
constexpr CsfTerm kCsfCx{1.0, 0.0053};
constexpr CsfTerm kCsfCz1{34.1, 0.04};
constexpr CsfTerm kCsfCz2{13.5, 0.025};

// Edges and points: derivatives of a Gaussian whose width w is 0.082 degrees; the filters use a
// standard deviation of w / 2.
constexpr double kFeatureWidthDegrees = 0.082;

double csf_shape(const CsfTerm& term, double x_degrees) {
  const double pi = std::numbers::pi;
  return std::exp(-pi * pi * x_degrees * x_degrees / term.b);
}

std::vector<double> sampled(const CsfTerm& term, int radius, double ppd) {
  std::vector<double> taps(static_cast<std::size_t>(radius) + 1);
  for (int i = 0; i <= radius; ++i) taps[static_cast<std::size_t>(i)] = csf_shape(term, i / ppd);
  return taps;
}

// Sum over the full kernel [-radius, radius] of a symmetric half kernel.
double full_sum(const std::vector<double>& half) {
  double sum = half[0];
  for (std::size_t i = 1; i < half.size(); ++i) sum += 2.0 * half[i];
  return sum;
}

HalfKernel scaled(const std::vector<double>& half, double factor) {
  HalfKernel k;
  for (double v : half) k.taps.push_back(static_cast<float>(v * factor));
  return k;
}

// out[x] = sum_i k[i] (in[x - i] + in[x + i]); `in` must be readable from -radius to n + radius.
void correlate_symmetric(const float* in, int n, const HalfKernel& k, float* out) {
  const float* taps = k.taps.data();
  for (int x = 0; x < n; ++x) out[x] = taps[0] * in[x];
  for (int i = 1; i <= k.radius(); ++i) {
    const float w = taps[i];
    for (int x = 0; x < n; ++x) out[x] += w * (in[x - i] + in[x + i]);
  }
}

// The three feature filters of one row at once: they share their input and radius.
void correlate_features(const float* in, int n, const FlipFilters& f, float* gauss, float* d1, float* d2) {
  const float *g = f.gauss.taps.data(), *k1 = f.d1.taps.data(), *k2 = f.d2.taps.data();
  for (int x = 0; x < n; ++x) {
    gauss[x] = g[0] * in[x];
    d1[x] = 0.0f;
    d2[x] = k2[0] * in[x];
  }
  for (int i = 1; i <= f.gauss.radius(); ++i) {
    const float wg = g[i], w1 = k1[i], w2 = k2[i];
    for (int x = 0; x < n; ++x) {
      const float sum = in[x - i] + in[x + i], difference = in[x + i] - in[x - i];
      gauss[x] += wg * sum;
      d1[x] += w1 * difference;
      d2[x] += w2 * sum;
    }
  }
}

// The vertical counterparts, on one plane of a band's ring of horizontally filtered rows: image
// row y (clamped to the image, which is clamp-to-edge) lives in slot y mod ring size.
struct Column {
  const float* ring;
  int width, height, slots;
  const float* row(int y) const {
    const int slot = std::clamp(y, 0, height - 1) % slots;
    return ring + static_cast<std::size_t>(slot) * static_cast<std::size_t>(width);
  }
};

void vertical_symmetric(const Column& c, int y, const HalfKernel& k, float* out, bool accumulate) {
  const float* taps = k.taps.data();
  const float* centre = c.row(y);
  for (int x = 0; x < c.width; ++x) out[x] = (accumulate ? out[x] : 0.0f) + taps[0] * centre[x];
  for (int i = 1; i <= k.radius(); ++i) {
    const float w = taps[i];
    const float *up = c.row(y - i), *down = c.row(y + i);
    for (int x = 0; x < c.width; ++x) out[x] += w * (up[x] + down[x]);
  }
}

// First and second vertical derivatives of the Gaussian-filtered plane at once.
void vertical_derivatives(const Column& c, int y, const FlipFilters& f, float* d1, float* d2) {
  const float *k1 = f.d1.taps.data(), *k2 = f.d2.taps.data();
  const float* centre = c.row(y);
  for (int x = 0; x < c.width; ++x) {
    d1[x] = 0.0f;
    d2[x] = k2[0] * centre[x];
  }
  for (int i = 1; i <= f.d1.radius(); ++i) {
    const float w1 = k1[i], w2 = k2[i];
    const float *up = c.row(y - i), *down = c.row(y + i);
    for (int x = 0; x < c.width; ++x) {
      d1[x] += w1 * (down[x] - up[x]);
      d2[x] += w2 * (up[x] + down[x]);
    }
  }
}

// The planes of one image in a band's ring: opponent channels through their CSF filters, and
// the luminance through the Gaussian and its two derivatives.
enum Plane { kY, kCx, kCz1, kCz2, kGauss, kD1, kD2, kPlanes };
// The rows the vertical pass makes per image: filtered opponent channels, then the luminance's
// dx, dy, dxx and dyy.
enum Result { kLum, kCxOut, kCzOut, kDx, kDy, kDxx, kDyy, kResults };

// The FLIP error of each pixel of a row from the vertical pass's results ([image][result][x]):
// colour^(1 - feature). `out` is declared unaliased: with fourteen input rows, proving that at
// run time is more than the compiler will try, and this loop must vectorise.
void pixel_errors(const ColourRemap& remap, const float* results, std::size_t n, float* __restrict out) {
  const auto row = [&](int image, int r) { return results + static_cast<std::size_t>(image * kResults + r) * n; };
  const float *rl = row(0, kLum), *rx = row(0, kCxOut), *rz = row(0, kCzOut);
  const float *rdx = row(0, kDx), *rdy = row(0, kDy), *rdxx = row(0, kDxx), *rdyy = row(0, kDyy);
  const float *tl = row(1, kLum), *tx = row(1, kCxOut), *tz = row(1, kCzOut);
  const float *tdx = row(1, kDx), *tdy = row(1, kDy), *tdxx = row(1, kDxx), *tdyy = row(1, kDyy);
  const ColourRemap k = remap;
  for (std::size_t x = 0; x < n; ++x) {
    const float c = colour_difference(k, rl[x], rx[x], rz[x], tl[x], tx[x], tz[x]);
    const float f = feature_difference(rdx[x], rdy[x], rdxx[x], rdyy[x], tdx[x], tdy[x], tdxx[x], tdyy[x]);
    out[x] = fast_pow(c, 1.0f - f);
  }
}

}  // namespace

FlipFilters::FlipFilters(double ppd) {
  // One radius for the four CSF kernels: three standard deviations of the widest Gaussian
  // (exp(-pi^2 x^2 / b) has a standard deviation of sqrt(b / (2 pi^2)) degrees).
  const double pi = std::numbers::pi;
  const double widest = std::max({kCsfY.b, kCsfCx.b, kCsfCz1.b, kCsfCz2.b});
  const int radius = static_cast<int>(std::ceil(3.0 * std::sqrt(widest / (2.0 * pi * pi)) * ppd));

  // Y and Cx: one Gaussian each, normalised so that the 2-D kernel sums to one (the constant
  // a sqrt(pi/b) cancels).
  const std::vector<double> y_half = sampled(kCsfY, radius, ppd), cx_half = sampled(kCsfCx, radius, ppd);
  y = scaled(y_half, 1.0 / full_sum(y_half));
  cx = scaled(cx_half, 1.0 / full_sum(cx_half));

  // Cz: c1 G1(x) G1(y) + c2 G2(x) G2(y), c = a sqrt(pi/b), normalised as a whole. Each term's 1-D
  // kernel carries sqrt(c / total) of the weight so that the two passes multiply out to it.
  const std::vector<double> g1 = sampled(kCsfCz1, radius, ppd), g2 = sampled(kCsfCz2, radius, ppd);
  const double c1 = kCsfCz1.a * std::sqrt(pi / kCsfCz1.b), c2 = kCsfCz2.a * std::sqrt(pi / kCsfCz2.b);
  const double s1 = full_sum(g1), s2 = full_sum(g2);
  const double total = c1 * s1 * s1 + c2 * s2 * s2;
  cz1 = scaled(g1, std::sqrt(c1 / total));
  cz2 = scaled(g2, std::sqrt(c2 / total));

  // Feature kernels, in pixels: the Gaussian sums to one; each derivative's positive taps sum to
  // one and its negative taps to minus one, so a unit step or spike gives a response of one.
  const double sigma = 0.5 * kFeatureWidthDegrees * ppd;
  const int feature_radius = static_cast<int>(std::ceil(3.0 * sigma));
  std::vector<double> g(static_cast<std::size_t>(feature_radius) + 1), dg(g.size()), ddg(g.size());
  for (int i = 0; i <= feature_radius; ++i) {
    const double x = i, value = std::exp(-x * x / (2.0 * sigma * sigma));
    g[static_cast<std::size_t>(i)] = value;
    dg[static_cast<std::size_t>(i)] = -x * value;
    ddg[static_cast<std::size_t>(i)] = (x * x / (sigma * sigma) - 1.0) * value;
  }
  gauss = scaled(g, 1.0 / full_sum(g));
  // g' is odd: its taps at +i are all negative (or zero), those at -i positive, equal in sum.
  double d1_positive = 0.0;
  for (std::size_t i = 1; i < dg.size(); ++i) d1_positive -= dg[i];
  d1 = scaled(dg, 1.0 / d1_positive);
  // g'' is even: negative at the centre, positive further out.
  double d2_positive = 0.0, d2_negative = 0.0;
  for (std::size_t i = 0; i < ddg.size(); ++i) {
    const double weight = i == 0 ? ddg[i] : 2.0 * ddg[i];
    (weight > 0.0 ? d2_positive : d2_negative) += weight;
  }
  d2.taps.clear();
  for (double v : ddg) d2.taps.push_back(static_cast<float>(v > 0.0 ? v / d2_positive : v / -d2_negative));
}

struct FlipPipeline::Scratch {
  std::vector<float> rgb, padded;  // one source row: linear RGB; lum, cx, cz with edge padding
  std::vector<float> ring;         // [image][plane][slot][x]
  std::vector<float> results;      // [image][result][x]
};

FlipPipeline::FlipPipeline(int width, int height, double pixels_per_degree)
    : width_(width), height_(height), filters_(pixels_per_degree), remap_(ColourRemap::make()) {
  pad_ = std::max(filters_.y.radius(), filters_.gauss.radius());
  ring_rows_ = 2 * pad_ + 1;
}

FlipPipeline::~FlipPipeline() = default;

void FlipPipeline::filter_row(const RowSource& source, int y, Scratch& s, int image) const {
  const int w = width_;
  const auto n = static_cast<std::size_t>(w), padded = n + 2 * static_cast<std::size_t>(pad_);
  float *r = s.rgb.data(), *g = r + n, *b = g + n;
  source(y, r, g, b);
  float* lum = s.padded.data() + pad_;
  float* cx = lum + padded;
  float* cz = cx + padded;
  for (int x = 0; x < w; ++x) {
    const Opponent o = to_opponent(r[x], g[x], b[x]);
    lum[x] = o.lum;
    cx[x] = o.cx;
    cz[x] = o.cz;
  }
  // Clamp to the edge: each row is padded with copies of its first and last pixel.
  for (float* row : {lum, cx, cz}) {
    std::fill(row - pad_, row, row[0]);
    std::fill(row + w, row + w + pad_, row[w - 1]);
  }
  const auto plane = [&](int p) {
    const std::size_t index = static_cast<std::size_t>(image * kPlanes + p) * static_cast<std::size_t>(ring_rows_) +
                              static_cast<std::size_t>(y % ring_rows_);
    return s.ring.data() + index * n;
  };
  correlate_symmetric(lum, w, filters_.y, plane(kY));
  correlate_symmetric(cx, w, filters_.cx, plane(kCx));
  correlate_symmetric(cz, w, filters_.cz1, plane(kCz1));
  correlate_symmetric(cz, w, filters_.cz2, plane(kCz2));
  correlate_features(lum, w, filters_, plane(kGauss), plane(kD1), plane(kD2));
}

void FlipPipeline::finish_row(int y, Scratch& s, float* error) const {
  const int w = width_;
  const auto n = static_cast<std::size_t>(w);
  const auto result = [&](int image, int r) {
    return s.results.data() + static_cast<std::size_t>(image * kResults + r) * n;
  };
  for (int image = 0; image < 2; ++image) {
    const auto column = [&](int p) {
      const std::size_t first = static_cast<std::size_t>(image * kPlanes + p) * static_cast<std::size_t>(ring_rows_);
      return Column{s.ring.data() + first * n, w, height_, ring_rows_};
    };
    vertical_symmetric(column(kY), y, filters_.y, result(image, kLum), false);
    vertical_symmetric(column(kCx), y, filters_.cx, result(image, kCxOut), false);
    vertical_symmetric(column(kCz1), y, filters_.cz1, result(image, kCzOut), false);
    vertical_symmetric(column(kCz2), y, filters_.cz2, result(image, kCzOut), true);
    // d/dx: the horizontal derivatives smoothed vertically; d/dy: the other way round.
    vertical_symmetric(column(kD1), y, filters_.gauss, result(image, kDx), false);
    vertical_symmetric(column(kD2), y, filters_.gauss, result(image, kDxx), false);
    vertical_derivatives(column(kGauss), y, filters_, result(image, kDy), result(image, kDyy));
  }
  pixel_errors(remap_, s.results.data(), n, error + static_cast<std::size_t>(y) * n);
}

void FlipPipeline::run_band(const RowSource& reference, const RowSource& test, int y0, int y1, Scratch& s,
                            float* error) const {
  if (s.ring.empty()) {  // first use, by the thread that will keep using it
    const auto n = static_cast<std::size_t>(width_);
    s.rgb.resize(3 * n);
    s.padded.resize(3 * (n + 2 * static_cast<std::size_t>(pad_)));
    s.ring.resize(2 * kPlanes * static_cast<std::size_t>(ring_rows_) * n);
    s.results.resize(2 * kResults * n);
  }
  int next = std::max(0, y0 - pad_);  // the next row to filter horizontally
  for (int y = y0; y < y1; ++y) {
    for (const int last = std::min(height_ - 1, y + pad_); next <= last; ++next) {
      filter_row(reference, next, s, 0);
      filter_row(test, next, s, 1);
    }
    finish_row(y, s, error);
  }
}

bool FlipPipeline::run(const RowSource& reference, const RowSource& test, float* error, ThreadPool& pool,
                       double stop_above) {
  const int threads = pool.size();
  if (scratch_.size() < static_cast<std::size_t>(threads)) scratch_.resize(static_cast<std::size_t>(threads));
  for (auto& s : scratch_) {
    if (!s) s = std::make_unique<Scratch>();
  }
  // A single thread takes the image as one band (nothing filtered twice); several threads take
  // four bands each, so that one slow thread does not hold up the rest, but no band is so short
  // that its overlap dominates. A run that may stop early takes bands of about 32 rows, so that
  // it can stop after a small part of the image.
  const bool may_stop = std::isfinite(stop_above);
  const int wanted = may_stop ? std::max(4 * threads, height_ / 32) : (threads == 1 ? 1 : 4 * threads);
  const int bands = std::min(wanted, std::max(1, height_ / (4 * pad_)));
  const int band_rows = (height_ + bands - 1) / bands;
  std::mutex sum_mutex;
  double sum = 0.0;
  std::atomic<bool> stopped{false};
  pool.parallel_for(static_cast<std::size_t>(bands), 1, [&](std::size_t begin, std::size_t end, int worker) {
    for (std::size_t band = begin; band < end; ++band) {
      if (stopped.load(std::memory_order_relaxed)) return;
      const int y0 = static_cast<int>(band) * band_rows, y1 = std::min(height_, y0 + band_rows);
      if (y0 >= y1) continue;
      run_band(reference, test, y0, y1, *scratch_[static_cast<std::size_t>(worker)], error);
      if (!may_stop) continue;
      double band_sum = 0.0;
      const std::size_t from = static_cast<std::size_t>(y0) * static_cast<std::size_t>(width_);
      const std::size_t to = static_cast<std::size_t>(y1) * static_cast<std::size_t>(width_);
      for (std::size_t i = from; i < to; ++i) band_sum += error[i];
      std::lock_guard lock(sum_mutex);
      sum += band_sum;
      if (sum > stop_above) stopped = true;
    }
  });
  return !stopped;
}

}  // namespace farm::flip_detail
