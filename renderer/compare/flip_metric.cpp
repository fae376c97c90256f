// flip: NVIDIA's FLIP (flip.h). LDR-FLIP for 8-bit images, which hold sRGB-encoded values;
// HDR-FLIP for EXRs, which hold linear ones.
#include <fmt/format.h>

#include "renderer/compare/flip.h"
#include "renderer/compare/metrics.h"
#include "renderer/util/thread_pool.h"

namespace farm {

CompareResult flip_metric(const Image& reference, const Image& test, const CompareSettings& s) {
  FlipOptions options;
  options.pixels_per_degree = s.pixels_per_degree;
  ThreadPool pool(s.threads);
  const bool ldr = reference.display_referred;
  const FlipResult flip = ldr ? flip_ldr(reference, test, options, &pool) : flip_hdr(reference, test, options, &pool);
  CompareResult result;
  result.verdict = flip.mean <= s.max_mean ? Verdict::pass : Verdict::fail;
  result.figures = {{"flip_mean", flip.mean}};
  if (!ldr) {
    result.figures.push_back({"start_exposure", flip.start_exposure});
    result.figures.push_back({"stop_exposure", flip.stop_exposure});
    result.figures.push_back({"exposures", static_cast<double>(flip.exposure_count)});
  }
  result.would_pass_key = "max_mean";
  result.would_pass_value = flip.mean;
  result.summary = fmt::format("{}-FLIP mean {:.4f} (needs <= {:g})", ldr ? "LDR" : "HDR", flip.mean, s.max_mean);
  result.difference = flip_magma(flip.error_map);
  return result;
}

}  // namespace farm
