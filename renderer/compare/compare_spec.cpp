#include "renderer/compare/compare_spec.h"

#include <fmt/format.h>

#include <string>
#include <vector>

namespace farm {

std::vector<std::string_view> compare_keys() {
  std::vector<std::string_view> keys = {"metric", "ssim_channels"};
  for (const ThresholdKey& key : threshold_keys()) keys.push_back(key.name);
  return keys;
}

CompareSettings read_compare_settings(const JsonValue& value, CompareSettings settings) {
  return read_compare_settings(value.object(compare_keys()), settings);
}

CompareSettings read_compare_settings(const JsonObject& object, CompareSettings settings) {
  if (auto m = object.get("metric")) {
    std::vector<std::string_view> names;
    for (Metric metric : kAllMetrics) names.push_back(to_string(metric));
    const auto metric = metric_from_string(m->string());
    if (!metric) m->fail(fmt::format("unknown metric '{}' (expected {})", m->string(), join_alternatives(names)));
    settings.metric = *metric;
  }
  if (auto c = object.get("ssim_channels")) {
    const auto channels = ssim_channels_from_string(c->string());
    if (!channels) c->fail(fmt::format("expected luminance or each, not '{}'", c->string()));
    settings.ssim_channels = *channels;
  }
  for (const ThresholdKey& key : threshold_keys()) {
    if (auto v = object.get(key.name)) settings.*key.field = v->real(NumberRange::between(key.min, key.max));
  }
  return settings;
}

}  // namespace farm
