#pragma once
// Strict, path-aware reading of JSON input files (job files, regression suites). Every failure
// is an InputError "<file>: <json.path>: <what>", so a user can find the offending value.
#include <cstdint>
#include <glm/vec3.hpp>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace farm {

// Parses `text`. Syntax errors read "<file>:<line>:<column>: JSON syntax error: ...". Duplicate
// keys and numbers that overflow a double are refused with their JSON path, because nlohmann
// would otherwise keep the last duplicate silently and reject the overflow without a place.
nlohmann::json parse_json_strict(const std::string& text, const std::string& file);

// "a.b" / "a[3]"; keys that are not plain identifiers are quoted: a["my key"].
std::string json_path_key(const std::string& parent, std::string_view key);
std::string json_path_index(const std::string& parent, std::size_t index);

// "a, b or c": the accepted alternatives in a message.
std::string join_alternatives(const std::vector<std::string_view>& names);

// Short description of a value for "expected X, got Y" messages: a string ("abc"), 3.5, ...
std::string describe_json(const nlohmann::json& value);

// Inclusive or exclusive bounds on a number; used only to check and to word the message.
struct NumberRange {
  std::optional<double> min, max;
  bool min_exclusive = false, max_exclusive = false;

  static NumberRange at_least(double v) { return {v, std::nullopt, false, false}; }
  static NumberRange above(double v) { return {v, std::nullopt, true, false}; }
  static NumberRange between(double lo, double hi) { return {lo, hi, false, false}; }
  static NumberRange open(double lo, double hi) { return {lo, hi, true, true}; }
};

class JsonObject;

// A place in a document, for a value checked there that was not read from it (a keyframed value
// at a frame, jobs/README.md): its checks and messages are JsonValue's, the number shown as JSON
// writes a double.
struct JsonPlace {
  std::string file;
  std::string path;

  JsonPlace key(std::string_view k) const { return {file, json_path_key(path, k)}; }
  JsonPlace index(std::size_t i) const { return {file, json_path_index(path, i)}; }
  [[noreturn]] void fail(std::string_view what) const;
  // JsonValue::real and vec3 of the number(s) `v`.
  float real(double v, const NumberRange& range = {}) const;
  glm::vec3 vec3(const double (&v)[3], const NumberRange& range = {}) const;
};

// A value inside a parsed document, together with its path for messages.
class JsonValue {
 public:
  JsonValue(const nlohmann::json& value, std::string path, const std::string& file)
      : value_(&value), path_(std::move(path)), file_(&file) {}

  const nlohmann::json& raw() const { return *value_; }
  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }
  JsonPlace place() const { return {*file_, path_}; }

  [[noreturn]] void fail(std::string_view what) const;
  [[noreturn]] void fail_expected(std::string_view expected) const;  // "expected X, got Y"

  // A finite JSON number (booleans are not numbers), stored as a float, within `range`.
  float real(const NumberRange& range = {}) const;
  // A JSON integer (or an integral number such as 1e3) within [min, max].
  std::int64_t integer(std::int64_t min = std::numeric_limits<std::int64_t>::min(),
                       std::int64_t max = std::numeric_limits<std::int64_t>::max()) const;
  int int32(int min = std::numeric_limits<int>::min(),
            int max = std::numeric_limits<int>::max()) const;
  std::uint64_t unsigned_integer() const;
  std::string string() const;
  bool boolean() const;
  // Exactly three numbers, each within `range`; element errors name the index.
  glm::vec3 vec3(const NumberRange& range = {}) const;

  std::vector<JsonValue> array() const;
  // An object whose keys must all be among `allowed`; the first other key is an error.
  JsonObject object(std::initializer_list<std::string_view> allowed) const;
  JsonObject object(std::vector<std::string_view> allowed) const;  // keys known only at run time

 private:
  const nlohmann::json* value_;
  std::string path_;
  const std::string* file_;
};

class JsonObject {
 public:
  // Checks only that `value` is an object; call reject_unknown_keys() to enforce `allowed`.
  JsonObject(const JsonValue& value, std::initializer_list<std::string_view> allowed);
  JsonObject(const JsonValue& value, std::vector<std::string_view> allowed);

  std::optional<JsonValue> get(std::string_view key) const;
  JsonValue require(std::string_view key) const;
  void reject_unknown_keys() const;
  const JsonValue& value() const { return value_; }

 private:
  JsonValue value_;
  std::vector<std::string_view> allowed_;
};

}  // namespace farm
