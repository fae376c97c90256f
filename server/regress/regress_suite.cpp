#include "server/regress/regress_suite.h"

#include <fmt/format.h>

#include <set>

#include "renderer/compare/compare_spec.h"
#include "renderer/job/job_limits.h"
#include "renderer/job/render_settings.h"
#include "renderer/util/input_error.h"
#include "renderer/util/json_reader.h"
#include "renderer/util/path_confinement.h"
#include "server/common/suite_file.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxTests = 10000;

// A file the suite writes or reads as a reference: it must lie inside the suite's folder, so a
// suite cannot be made to overwrite (--update) or read files elsewhere.
fs::path reference_inside(const JsonValue& value, const fs::path& folder) {
  const std::string text = value.string();
  if (text.empty()) value.fail("an empty path");
  const fs::path path = resolve_from(folder, text);
  if (!resolve_within(folder, path)) {
    value.fail(fmt::format("'{}' lies outside the suite's folder {}; references must be inside it", text, folder.string()));
  }
  return path;
}

RenderOverrides read_render(const JsonValue& value) {
  const JsonObject o = value.object({"engine", "width", "height", "spp", "max_depth", "seed", "tile_size"});
  RenderOverrides r;
  if (auto v = o.get("engine")) {
    std::vector<std::string_view> names(std::begin(kEngineNames), std::end(kEngineNames));
    const std::string engine = v->string();
    if (!engine_from_string(engine)) v->fail(fmt::format("unknown engine '{}' (expected {})", engine, join_alternatives(names)));
    r.engine = engine;
  }
  if (auto v = o.get("width")) r.width = v->int32(1, kMaxImageSide);
  if (auto v = o.get("height")) r.height = v->int32(1, kMaxImageSide);
  if (auto v = o.get("spp")) r.spp = v->int32(1, kMaxSpp);
  if (auto v = o.get("max_depth")) r.max_depth = v->int32(-1, 1 << 20);
  if (auto v = o.get("seed")) r.seed = v->unsigned_integer();
  if (auto v = o.get("tile_size")) r.tile_size = v->int32(1, kMaxTileSize);
  return r;
}

}  // namespace

RegressSuite load_regress_suite(const fs::path& file) {
  RegressSuite suite;
  suite.file = fs::weakly_canonical(fs::absolute(file));
  suite.folder = suite.file.parent_path();
  const std::string text = read_bounded_text(file);
  const std::string name = file.string();
  const nlohmann::json doc = parse_json_strict(text, name);
  const JsonValue root(doc, "", name);
  const JsonObject top = root.object({"version", "name", "references", "asset_root", "compare", "tests"});
  top.require("version").int32(1, 1);
  const JsonValue suite_name = top.require("name");
  suite.name = suite_name.string();
  if (!is_safe_name(suite.name)) suite_name.fail("a name of letters, digits, '-', '_' and '.' (it names the report folder)");

  fs::path references = suite.folder / "refs";
  if (auto r = top.get("references")) references = reference_inside(*r, suite.folder);
  suite.asset_root = read_folder(top.get("asset_root"), suite.folder);
  CompareSettings defaults;
  if (auto c = top.get("compare")) defaults = read_compare_settings(*c, defaults);

  const JsonValue tests = top.require("tests");
  const std::vector<JsonValue> items = tests.array();
  if (items.empty()) tests.fail("a suite needs at least one test");
  if (items.size() > kMaxTests) tests.fail(fmt::format("more than {} tests", kMaxTests));
  std::set<std::string> names;
  for (const JsonValue& item : items) {
    const JsonObject t = item.object({"name", "job", "render", "compare", "reference"});
    RegressTest test;
    const JsonValue test_name = t.require("name");
    test.name = test_name.string();
    if (!is_safe_name(test.name)) test_name.fail("a name of letters, digits, '-', '_' and '.' (it names the test's files)");
    if (!names.insert(test.name).second) test_name.fail(fmt::format("a second test named '{}'", test.name));
    test.job = read_job_path(t.require("job"), suite.folder);
    if (auto r = t.get("render")) test.render = read_render(*r);
    test.compare = defaults;
    if (auto c = t.get("compare")) test.compare = read_compare_settings(*c, defaults);
    test.reference = references / (test.name + ".exr");
    if (auto r = t.get("reference")) test.reference = reference_inside(*r, suite.folder);
    suite.tests.push_back(std::move(test));
  }
  return suite;
}

}  // namespace farm
