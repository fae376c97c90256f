#pragma once
// NVIDIA's FLIP image difference (Andersson et al., "FLIP: A Difference Evaluator for Alternating
// Images", HPG 2020; HDR-FLIP, "Visualizing and Communicating Errors in Rendered Images", Ray
// Tracing Gems II, 2021), written from the papers: a per-pixel perceived error in [0, 1] from a
// colour pipeline (spatial contrast sensitivity filters in YyCxCz, Hunt-adjusted L*a*b*, HyAB
// distance) and a feature pipeline (edges and points of the achromatic channel), combined as
// colour^(1 - feature). HDR-FLIP tone-maps both images at a range of exposures and keeps each
// pixel's largest LDR-FLIP error.
#include <limits>

#include "renderer/compare/image.h"

namespace farm {

class ThreadPool;

struct FlipOptions {
  // Pixels per degree of visual angle: the paper's default viewer (0.7 m from a 0.7 m wide
  // monitor of 3840 pixels) sees 67.0206 pixels per degree.
  double pixels_per_degree = 67.0206;
  // HDR only: the exposure range in stops; computed from the reference image when not set
  // (the paper's automatic range), as flip-evaluator does.
  bool automatic_exposures = true;
  double start_exposure = 0.0, stop_exposure = 0.0;
  int exposure_count = 0;  // 0: max(2, ceil(stop - start)) as in the paper
  // LDR only: a caller that only asks "is the mean at most this?" may let the evaluation stop
  // once the errors summed so far put the mean above it. The result's mean is then above the
  // bound but not the image's mean (`complete` false), and the map has zeros where it stopped.
  double stop_when_mean_exceeds = std::numeric_limits<double>::infinity();
};

struct FlipResult {
  double mean = 0.0;           // the mean of the error map: the figure FLIP reports
  bool complete = true;        // false when stop_when_mean_exceeds cut the evaluation short
  Image error_map;             // one channel "FLIP", values in [0, 1]
  double start_exposure = 0.0, stop_exposure = 0.0;  // HDR: the range used
  int exposure_count = 0;                            // HDR: how many exposures were evaluated
};

// LDR-FLIP on two images of the same size whose colour channels (colour_channels()) are
// sRGB-encoded values in [0, 1] (a PNG or JPEG as read_image gives it). Throws
// std::invalid_argument on a size mismatch or missing colour channels.
FlipResult flip_ldr(const Image& reference, const Image& test, const FlipOptions& options,
                    ThreadPool* pool = nullptr);

// HDR-FLIP on two linear images (EXR) of the same size.
FlipResult flip_hdr(const Image& reference, const Image& test, const FlipOptions& options,
                    ThreadPool* pool = nullptr);

// The error map through the magma colour map, as FLIP's tools show it: channels R G B.
Image flip_magma(const Image& error_map);

}  // namespace farm
