#include "renderer/job/render_settings.h"

#include <algorithm>
#include <cstdint>
#include <fmt/format.h>

#include "renderer/util/input_error.h"

namespace farm {

std::string_view to_string(EngineKind e) {
  const auto i = static_cast<std::size_t>(e);
  return i < kEngineNames.size() ? kEngineNames[i] : "?";
}

std::optional<EngineKind> engine_from_string(std::string_view s) {
  for (std::size_t i = 0; i < kEngineNames.size(); ++i) {
    if (kEngineNames[i] == s) return static_cast<EngineKind>(i);
  }
  return std::nullopt;
}

std::string_view to_string(LightSampling l) {
  return l == LightSampling::NeeMis ? "nee-mis" : "bsdf";
}

std::optional<LightSampling> light_sampling_from_string(std::string_view s) {
  for (LightSampling l : {LightSampling::NeeMis, LightSampling::BsdfOnly}) {
    if (to_string(l) == s) return l;
  }
  return std::nullopt;
}

namespace {

// The engines render at least one sample per pixel whatever spp says.
int samples_per_pixel(const RenderSettings& settings) { return std::max(1, settings.spp); }

}  // namespace

int pass_count(const RenderSettings& settings) {
  if (settings.pass_spp < 0) {
    throw InputError(fmt::format("render.pass_spp: {} is negative (0 renders all samples in one pass)",
                                 settings.pass_spp));
  }
  const int spp = samples_per_pixel(settings);
  if (settings.engine != EngineKind::Path || settings.pass_spp == 0 || settings.pass_spp >= spp) return 1;
  // In 64 bits: spp + pass_spp may pass INT_MAX for settings built in code.
  const std::int64_t n = settings.pass_spp;
  return static_cast<int>((spp + n - 1) / n);  // the last pass may be short
}

SampleRange pass_samples(const RenderSettings& settings, int pass) {
  const int passes = pass_count(settings);
  if (pass < 0 || pass >= passes) {
    throw InputError(fmt::format("render.pass: pass {} is out of range: the {} engine renders spp {} "
                                 "in {} pass{} (0..{})",
                                 pass, to_string(settings.engine), settings.spp, passes,
                                 passes == 1 ? "" : "es", passes - 1));
  }
  const int spp = samples_per_pixel(settings);
  if (passes == 1) return {0, spp};
  // pass < ceil(spp / pass_spp), so pass * pass_spp < spp; (pass + 1) * pass_spp may not be.
  const std::int64_t n = settings.pass_spp;
  return {static_cast<int>(pass * n), static_cast<int>(std::min<std::int64_t>(spp, (pass + 1) * n))};
}

SampleRange samples_to_render(const RenderSettings& settings) {
  if (settings.pass == -1) {
    static_cast<void>(pass_count(settings));  // a negative pass_spp is refused all the same
    return {0, samples_per_pixel(settings)};
  }
  return pass_samples(settings, settings.pass);
}

}  // namespace farm
