#include "renderer/compare/compare_json.h"

#include <cmath>

namespace farm {

nlohmann::ordered_json json_number(double value) {
  if (std::isnan(value)) return nullptr;
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return value;
}

nlohmann::ordered_json to_json(const CompareResult& result) {
  nlohmann::ordered_json figures = nlohmann::ordered_json::object();
  for (const Figure& f : result.figures) figures[f.name] = json_number(f.value);
  nlohmann::ordered_json out = {{"metric", std::string(to_string(result.metric))},
                        {"verdict", std::string(to_string(result.verdict))},
                        {"summary", result.summary},
                        {"figures", figures}};
  if (!result.would_pass_key.empty()) {
    out["would_pass"] = {{"key", result.would_pass_key}, {"value", json_number(result.would_pass_value)}};
  }
  return out;
}

}  // namespace farm
