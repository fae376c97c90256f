#include "server/regress/regress_summary.h"

#include <fmt/format.h>

#include "renderer/compare/compare_json.h"

namespace farm {

std::string RegressCounts::line() const {
  // A failure whose reference --update just wrote is no failure any more: counted as written.
  std::string out = fmt::format("{} passed, {} failed", passed + warned, failed_not_updated + errors);
  if (warned > 0) out += fmt::format(", {} with warnings", warned);
  if (errors > 0) out += fmt::format(" ({} could not be rendered or compared)", errors);
  if (skipped > 0) out += fmt::format(", {} skipped", skipped);
  if (updated > 0) {
    out += fmt::format(", {} reference{} written ({} new)", updated, updated == 1 ? "" : "s", created);
  }
  return out;
}

int RegressCounts::exit_code() const { return failed_not_updated > 0 || errors > 0 ? 1 : 0; }

RegressCounts count_outcomes(const std::vector<TestOutcome>& outcomes) {
  RegressCounts c;
  for (const TestOutcome& o : outcomes) {
    switch (o.status) {
      case TestStatus::passed: ++c.passed; break;
      case TestStatus::warned: ++c.warned; break;
      case TestStatus::failed: ++c.failed, c.failed_not_updated += o.reference_updated ? 0 : 1; break;
      case TestStatus::error: ++c.errors; break;
      case TestStatus::skipped: ++c.skipped; break;
    }
    c.updated += o.reference_updated ? 1 : 0;
    c.created += o.reference_updated && o.reference_missing ? 1 : 0;
    c.seconds += o.seconds;
  }
  return c;
}

nlohmann::ordered_json outcome_json(const TestOutcome& o) {
  nlohmann::ordered_json out = {{"name", o.name},
                                {"status", std::string(to_string(o.status))},
                                {"metric", std::string(to_string(o.settings.metric))},
                                {"message", o.message},
                                {"seconds", o.seconds},
                                {"reference", o.reference.string()}};
  if (!o.new_image.empty()) out["new"] = o.new_image.string();
  nlohmann::ordered_json thresholds = nlohmann::ordered_json::object();
  for (const ThresholdKey& key : threshold_keys())
    if (key.metric == o.settings.metric) thresholds[std::string(key.name)] = json_number(o.settings.*key.field);
  out["thresholds"] = thresholds;
  if (!o.result.figures.empty()) {
    const nlohmann::ordered_json result = to_json(o.result);
    out["figures"] = result["figures"];
    if (result.contains("would_pass")) out["would_pass"] = result["would_pass"];
  }
  nlohmann::ordered_json images = nlohmann::ordered_json::object();
  if (!o.reference_png.empty()) images["reference"] = o.reference_png.filename().string();
  if (!o.new_png.empty()) images["new"] = o.new_png.filename().string();
  if (!o.difference_png.empty()) images["difference"] = o.difference_png.filename().string();
  out["images"] = images;
  out["reference_missing"] = o.reference_missing;
  out["reference_updated"] = o.reference_updated;
  return out;
}

nlohmann::ordered_json summary_json(const RegressSuite& suite, const std::vector<TestOutcome>& outcomes) {
  const RegressCounts c = count_outcomes(outcomes);
  nlohmann::ordered_json tests = nlohmann::ordered_json::array();
  for (const TestOutcome& o : outcomes) tests.push_back(outcome_json(o));
  return {{"suite", suite.name},
          {"file", suite.file.string()},
          {"counts",
           {{"passed", c.passed}, {"warned", c.warned}, {"failed", c.failed}, {"errors", c.errors},
            {"skipped", c.skipped}, {"references_written", c.updated}}},
          {"summary", c.line()},
          {"tests", tests}};
}

}  // namespace farm
