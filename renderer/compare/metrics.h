#pragma once
// The metrics behind compare_images, one file each. Each is called with images already checked
// to be the same size; each fills the verdict, summary, figures and would-pass threshold of its
// result (compare.cpp adds the difference image).
#include "renderer/compare/compare.h"

namespace farm {

CompareResult exact_metric(const Image& reference, const Image& test);
CompareResult threshold_metric(const Image& reference, const Image& test, const CompareSettings& settings);
CompareResult psnr_metric(const Image& reference, const Image& test, const CompareSettings& settings);
CompareResult ssim_metric(const Image& reference, const Image& test, const CompareSettings& settings);
CompareResult flip_metric(const Image& reference, const Image& test, const CompareSettings& settings);
CompareResult ztest_metric(const Image& reference, const Image& test, const CompareSettings& settings);

// |a - b| x 16 of the colour channels, as Blender's test reports show a difference.
Image absolute_difference_x16(const Image& reference, const Image& test);

// The mean SSIM (Wang et al. 2004: Gaussian window, sigma 1.5, radius 5, K1 0.01, K2 0.03,
// dynamic range 1) of one plane of each image, over the pixels whose window lies inside the
// image, as scikit-image's structural_similarity(gaussian_weights=True,
// use_sample_covariance=False, data_range=1) reports it. Both planes are width x height and
// larger than 10 pixels a side.
double mean_ssim(const std::vector<float>& a, const std::vector<float>& b, int width, int height);

}  // namespace farm
