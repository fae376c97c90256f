#pragma once
// Compares a new image with its reference by one metric and says PASS, WARN or FAIL, with the
// figures behind the verdict and a difference image. Images that cannot be compared (sizes or
// channel sets differ, no variance for the z-test) FAIL with the reason; nothing here throws on
// image content.
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "renderer/compare/compare_settings.h"
#include "renderer/compare/image.h"

namespace farm {

enum class Verdict { pass, warn, fail };
std::string_view to_string(Verdict verdict);  // PASS, WARN, FAIL

struct Figure {
  std::string name;  // e.g. mean_error, psnr_db, flip_mean, pass_percent
  double value = 0.0;
};

struct CompareResult {
  Metric metric = Metric::threshold;
  Verdict verdict = Verdict::fail;
  std::string summary;           // one line: the deciding figures, or why it could not compare
  std::vector<Figure> figures;   // in the order they are reported
  // The threshold that would have given PASS (e.g. "fail" 0.0213 at the given fail_percent, or
  // "min_psnr" 27.4): the value a suite could be loosened to. Empty key when none applies.
  std::string would_pass_key;
  double would_pass_value = std::numeric_limits<double>::quiet_NaN();
  Image difference;              // display values: |a-b| x16, the FLIP map or the z-test p-map

  double figure(std::string_view name) const;  // NaN when absent
};

CompareResult compare_images(const Image& reference, const Image& test, const CompareSettings& settings);

}  // namespace farm
