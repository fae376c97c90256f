#pragma once
// The LDR-FLIP pipeline on linear RGB, shared by flip_ldr (one run on the decoded sRGB images)
// and flip_hdr (one run per exposure on the tone-mapped images). Internal to renderer/compare.
//
// Every image is handled as contiguous float rows of its channels and filtered separably: a
// horizontal pass makes, per image, the row-filtered planes the two pipelines need; a vertical
// pass completes the filters for one output row and turns each of its pixels into its FLIP error.
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "renderer/compare/flip_colour.h"

namespace farm {

class ThreadPool;

namespace flip_detail {

// Writes row y of an image as linear RGB in [0, 1] into r, g and b (width values each).
using RowSource = std::function<void(int y, float* r, float* g, float* b)>;

// Half of a symmetric (or antisymmetric) 1-D kernel: taps[i] is the weight at offset +i; the
// weight at -i is taps[i] (symmetric) or -taps[i] (antisymmetric, taps[0] = 0).
struct HalfKernel {
  std::vector<float> taps;
  int radius() const { return static_cast<int>(taps.size()) - 1; }
};

// The filters of one viewing condition (pixels per degree).
struct FlipFilters {
  explicit FlipFilters(double pixels_per_degree);
  // Contrast sensitivity of the achromatic (Y), red-green (Cx) and blue-yellow (Cz) channels.
  // Cz's is a sum of two Gaussians, so its 2-D kernel is cz1(x) cz1(y) + cz2(x) cz2(y).
  HalfKernel y, cx, cz1, cz2;
  // Edge and point detection: a Gaussian and its first and second derivatives.
  HalfKernel gauss, d1, d2;
};

// Evaluates LDR-FLIP for images of one size. The image is cut into bands of rows, each finished
// by one thread: it filters rows horizontally into a ring of the last 2r + 1 rows (r: the largest
// kernel radius) and, as soon as a row's vertical neighbourhood is there, completes that row.
// So no full-size intermediate plane is ever written (14 of them would be 116 MB at 1080p, and
// faulting them in, writing and re-reading them cost more than the arithmetic they save); the
// price is that the r rows either side of a band are filtered horizontally twice. Scratch memory is kept between runs, so the
// exposures of HDR-FLIP reuse it.
class FlipPipeline {
 public:
  FlipPipeline(int width, int height, double pixels_per_degree);
  ~FlipPipeline();

  // Writes the per-pixel FLIP error of `test` against `reference` to error[y * width + x].
  // With a finite `stop_above`, bands not yet started are skipped once the errors summed so far
  // exceed it (their errors stay 0): for a caller that only asks whether the mean is below a
  // bound. Returns whether every band ran.
  bool run(const RowSource& reference, const RowSource& test, float* error, ThreadPool& pool,
           double stop_above = std::numeric_limits<double>::infinity());

 private:
  struct Scratch;
  void filter_row(const RowSource& source, int y, Scratch& s, int image) const;
  void finish_row(int y, Scratch& s, float* error) const;
  void run_band(const RowSource& reference, const RowSource& test, int y0, int y1, Scratch& s,
                float* error) const;

  int width_, height_;
  FlipFilters filters_;
  ColourRemap remap_;
  int pad_;         // the largest radius of any kernel: how far a row and a column reach
  int ring_rows_;   // 2 pad + 1 rows of horizontally filtered planes per band
  std::vector<std::unique_ptr<Scratch>> scratch_;  // one per pool thread, made on first use
};

}  // namespace flip_detail
}  // namespace farm
