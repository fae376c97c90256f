// ssim: the structural similarity index of Wang, Bovik, Sheikh and Simoncelli (2004), with their
// 11x11 Gaussian window (sigma 1.5) and constants, on Rec. 709 luminance or on each colour
// channel. Only pixels whose whole window lies inside the image are averaged, as scikit-image
// does, so no border rule enters the figure.
#include <fmt/format.h>

#include <cmath>
#include <vector>

#include "renderer/compare/metrics.h"

namespace farm {
namespace {

constexpr int kRadius = 5;        // the window is 2 * 5 + 1 = 11 pixels, sigma 1.5 truncated at 3.5 sigma
constexpr double kSigma = 1.5;

std::vector<double> gaussian_weights() {
  std::vector<double> w(2 * kRadius + 1);
  double sum = 0.0;
  for (int i = -kRadius; i <= kRadius; ++i) sum += w[static_cast<std::size_t>(i + kRadius)] = std::exp(-0.5 * i * i / (kSigma * kSigma));
  for (double& v : w) v /= sum;
  return w;
}

// One plane of the image: luminance, or a single channel.
std::vector<float> plane(const Image& image, const std::vector<int>& channels, int which, bool luminance) {
  std::vector<float> out(image.pixel_count());
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) + static_cast<std::size_t>(x);
      if (luminance && channels.size() == 3) {
        out[i] = 0.2126f * image.at(x, y, channels[0]) + 0.7152f * image.at(x, y, channels[1]) +
                 0.0722f * image.at(x, y, channels[2]);
      } else {
        out[i] = image.at(x, y, channels[static_cast<std::size_t>(which)]);
      }
    }
  return out;
}

}  // namespace

double mean_ssim(const std::vector<float>& a, const std::vector<float>& b, int width, int height) {
  static const std::vector<double> w = gaussian_weights();
  constexpr double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;  // (K L)^2 with L = 1
  const int inner_w = width - 2 * kRadius, inner_h = height - 2 * kRadius;
  const auto W = static_cast<std::size_t>(width);
  // Horizontal pass: the five windowed moments (a, b, a^2, b^2, ab) at every interior column of
  // every row; then the vertical pass at interior rows.
  std::vector<double> h(5 * static_cast<std::size_t>(height) * static_cast<std::size_t>(inner_w));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < inner_w; ++x) {
      double m[5] = {0, 0, 0, 0, 0};
      for (int k = 0; k <= 2 * kRadius; ++k) {
        const std::size_t i = static_cast<std::size_t>(y) * W + static_cast<std::size_t>(x + k);
        const double wa = w[static_cast<std::size_t>(k)], va = a[i], vb = b[i];
        m[0] += wa * va, m[1] += wa * vb, m[2] += wa * va * va, m[3] += wa * vb * vb, m[4] += wa * va * vb;
      }
      double* out = &h[5 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(inner_w) + static_cast<std::size_t>(x))];
      for (int j = 0; j < 5; ++j) out[j] = m[j];
    }
  double total = 0.0;
  for (int y = 0; y < inner_h; ++y)
    for (int x = 0; x < inner_w; ++x) {
      double m[5] = {0, 0, 0, 0, 0};
      for (int k = 0; k <= 2 * kRadius; ++k) {
        const double* in = &h[5 * (static_cast<std::size_t>(y + k) * static_cast<std::size_t>(inner_w) + static_cast<std::size_t>(x))];
        for (int j = 0; j < 5; ++j) m[j] += w[static_cast<std::size_t>(k)] * in[j];
      }
      const double mu_a = m[0], mu_b = m[1];
      const double var_a = m[2] - mu_a * mu_a, var_b = m[3] - mu_b * mu_b, cov = m[4] - mu_a * mu_b;
      total += ((2.0 * mu_a * mu_b + c1) * (2.0 * cov + c2)) / ((mu_a * mu_a + mu_b * mu_b + c1) * (var_a + var_b + c2));
    }
  return total / (static_cast<double>(inner_w) * static_cast<double>(inner_h));
}

CompareResult ssim_metric(const Image& reference, const Image& test, const CompareSettings& s) {
  CompareResult result;
  if (reference.width <= 2 * kRadius || reference.height <= 2 * kRadius) {
    result.verdict = Verdict::fail;
    result.summary = fmt::format("SSIM needs images larger than {0}x{0} pixels", 2 * kRadius);
    return result;
  }
  const std::vector<int> a_channels = colour_channels(reference), b_channels = colour_channels(test);
  const bool luminance = s.ssim_channels == SsimChannels::luminance;
  const int planes = luminance ? 1 : static_cast<int>(a_channels.size());
  double sum = 0.0;
  for (int p = 0; p < planes; ++p) {
    sum += mean_ssim(plane(reference, a_channels, p, luminance), plane(test, b_channels, p, luminance), reference.width,
                     reference.height);
  }
  const double ssim = sum / planes;
  result.verdict = ssim >= s.min_ssim ? Verdict::pass : Verdict::fail;  // NaN (a NaN pixel) fails
  result.figures = {{"ssim", ssim}};
  result.would_pass_key = "min_ssim";
  result.would_pass_value = ssim;
  result.summary = fmt::format("mean SSIM {:.4f} on {} (needs {:g})", ssim, luminance ? "luminance" : "each channel",
                               s.min_ssim);
  return result;
}

}  // namespace farm
