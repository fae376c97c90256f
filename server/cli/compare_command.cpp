#include "server/cli/compare_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "renderer/compare/compare.h"
#include "renderer/compare/compare_json.h"
#include "renderer/job/job_limits.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

struct CompareCommandOptions {
  fs::path reference, test;
  std::string metric = "threshold";
  std::string ssim_channels = "luminance";
  CompareSettings settings;
  std::optional<fs::path> diff;
  bool json = false;
};

std::string dashed(std::string_view key) {
  std::string flag(key);
  for (char& c : flag)
    if (c == '_') c = '-';
  return flag;
}

std::string describe(const fs::path& file, const Image& image) {
  return fmt::format("{}  {}x{}  {}{}", file.string(), image.width, image.height, fmt::join(image.channels, " "),
                     image.display_referred ? " (8-bit, sRGB-encoded)" : "");
}

void print_human(const CompareCommandOptions& o, const Image& reference, const Image& test, const CompareResult& r) {
  fmt::print("reference  {}\n", describe(o.reference, reference));
  fmt::print("new        {}\n", describe(o.test, test));
  fmt::print("{:<10} {}\n", to_string(r.metric), r.summary);
  for (const Figure& f : r.figures) fmt::print("           {:<22} {:.6g}\n", f.name, f.value);
  if (!r.would_pass_key.empty() && std::isfinite(r.would_pass_value)) {
    fmt::print("           would pass with --{} {:.6g}\n", dashed(r.would_pass_key), r.would_pass_value);
  }
  if (o.diff) fmt::print("diff       {}\n", o.diff->string());
  fmt::print("{}\n", to_string(r.verdict));
}

int run_compare_command(CompareCommandOptions& o) {
  o.settings.metric = *metric_from_string(o.metric);  // CLI11 checked the name
  o.settings.ssim_channels = *ssim_channels_from_string(o.ssim_channels);
  // Sizes from the headers first: images of different sizes fail without a pixel decoded.
  const auto [reference, test] = read_images_to_compare(o.reference, o.test);
  const CompareResult result = compare_images(reference, test, o.settings);
  if (o.diff && result.difference.pixel_count() > 0) {
    if (o.diff->extension() == ".exr") {
      write_exr_image(result.difference, *o.diff);
    } else {
      write_png_image(result.difference, *o.diff);
    }
  }
  if (o.json) {
    nlohmann::ordered_json out = to_json(result);
    out["reference"] = o.reference.string();
    out["new"] = o.test.string();
    if (o.diff) out["diff"] = o.diff->string();
    fmt::print("{}\n", out.dump(2));
  } else {
    print_human(o, reference, test, result);
  }
  return result.verdict == Verdict::fail ? 1 : 0;
}

std::string metric_names() {
  std::vector<std::string_view> names;
  for (Metric m : kAllMetrics) names.push_back(to_string(m));
  return fmt::format("{}", fmt::join(names, ", "));
}

}  // namespace

void add_compare_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<CompareCommandOptions>();
  CLI::App* compare = app.add_subcommand("compare", "Compare an image with its reference: PASS, WARN or FAIL");
  compare->add_option("REF", o->reference, "The reference image (EXR, PNG or JPEG)")->required();
  compare->add_option("NEW", o->test, "The image to check against it")->required();
  std::vector<std::string> metrics;
  for (Metric m : kAllMetrics) metrics.emplace_back(to_string(m));
  compare->add_option("--metric", o->metric,
                      "exact: bit-identical; threshold: idiff's rule; psnr; ssim; flip (LDR for PNG/JPEG, HDR "
                      "for EXR); ztest: Monte Carlo noise test on the variance AOV (default threshold)")
      ->check(CLI::IsMember(metrics));
  for (const ThresholdKey& key : threshold_keys()) {
    double CompareSettings::*field = key.field;
    compare
        ->add_option_function<double>(
            "--" + dashed(key.name), [o, field](double value) { o->settings.*field = value; },
            fmt::format("{} [{}; default {:g}]", key.help, to_string(key.metric), CompareSettings{}.*field))
        ->check(CLI::Validator(
            [min = key.min, max = key.max](std::string& text) -> std::string {
              const double v = std::stod(text);
              if (std::isnan(v) || v < min || v > max) return fmt::format("{} is outside [{:g}, {:g}]", text, min, max);
              return {};
            },
            "NUMBER"));
  }
  compare->add_option("--ssim-channels", o->ssim_channels, "SSIM of luminance (default) or the mean over each colour channel")
      ->check(CLI::IsMember({"luminance", "each"}));
  compare->add_option("--threads", o->settings.threads, "Threads for FLIP (default: all)")
      ->check(CLI::Range(0, kMaxThreads));
  compare->add_option("--diff", o->diff,
                      "Write the difference image: |ref - new| x16, the FLIP error map (magma) or the z-test "
                      "p-map (red: failing pixels); PNG, or EXR by extension");
  compare->add_flag("--json", o->json, "Print the verdict and figures as JSON");
  compare->footer(fmt::format("Metrics: {}. Threshold flags are idiff's with the same defaults (fail and warn 1e-6, "
                              "percentages 0), so `idiff -fail F -failpercent P REF NEW` gives the same verdict.\n"
                              "Exit codes: 0 PASS or WARN, 1 FAIL (including images of different sizes or channels), "
                              "2 bad input (a file that is missing or not an image).",
                              metric_names()));
  commands.add(compare, [o] { return run_compare_command(*o); });
}

}  // namespace farm
