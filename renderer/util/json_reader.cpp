#include "renderer/util/json_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "renderer/util/input_error.h"
#include "renderer/util/utf8_text.h"

namespace farm {

namespace {

using Json = nlohmann::json;

constexpr std::size_t kMaxShownChars = 48;
constexpr std::size_t kMaxShownPath = 240;

bool is_identifier(std::string_view key) {
  if (key.empty()) return false;
  auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
  if (!alpha(key.front())) return false;
  return std::all_of(key.begin(), key.end(), [&](char c) {
    return alpha(c) || (c >= '0' && c <= '9') || c == '-';
  });
}

// A path from hostile input can be enormous (deep nesting); keep its tail, which names the place.
std::string shown_path(const std::string& path) {
  if (path.size() <= kMaxShownPath) return path;
  return "..." + path.substr(path.size() - kMaxShownPath);
}

[[noreturn]] void throw_at(const std::string& file, const std::string& path,
                           std::string_view what) {
  if (path.empty()) throw InputError(fmt::format("{}: {}", file, what));
  throw InputError(fmt::format("{}: {}: {}", file, shown_path(path), what));
}

// Builds the document like nlohmann's DOM parser, but knows the path of every value, so it can
// name the place of a duplicate key or of a number too large for a double.
class StrictDomBuilder final : public nlohmann::json_sax<Json> {
 public:
  StrictDomBuilder(const std::string& text, const std::string& file) : text_(text), file_(file) {}

  Json take() { return std::move(root_); }

  bool null() override { return add(nullptr); }
  bool boolean(bool v) override { return add(v); }
  bool number_integer(number_integer_t v) override { return add(v); }
  bool number_unsigned(number_unsigned_t v) override { return add(v); }
  bool number_float(number_float_t v, const string_t&) override { return add(v); }
  bool string(string_t& v) override { return add(std::move(v)); }
  bool binary(binary_t&) override { return add(nullptr); }  // JSON text never has binary

  bool start_object(std::size_t) override { return open(Json::object()); }
  bool key(string_t& k) override {
    Frame& top = stack_.back();
    if (top.node->contains(k)) throw_at(file_, json_path_key(node_path(), k), "duplicate key");
    top.key = k;
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(Json::array()); }
  bool end_array() override { return close(); }

  bool parse_error(std::size_t position, const std::string& token,
                   const nlohmann::detail::exception& ex) override {
    if (ex.id == 406) {  // out_of_range: a number literal that overflows a double
      throw_at(file_, pending_path(),
               fmt::format("number {} is out of range (not finite as a double)",
                           utf8_prefix(token, kMaxShownChars)));
    }
    const auto [line, column] = line_and_column(position);
    throw InputError(fmt::format("{}:{}:{}: JSON syntax error: {}", file_, line, column,
                                 syntax_detail(ex.what())));
  }

 private:
  struct Frame {
    Json* node;
    std::string key;  // the key whose value is being read (objects only)
  };

  bool add(Json value) {
    place(std::move(value));
    return true;
  }
  bool open(Json container) {
    Json* slot = place(std::move(container));
    stack_.push_back({slot, {}});
    return true;
  }
  bool close() {
    stack_.pop_back();
    return true;
  }
  Json* place(Json value) {
    if (stack_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    Frame& top = stack_.back();
    if (top.node->is_array()) {
      top.node->push_back(std::move(value));
      return &top.node->back();
    }
    Json& slot = (*top.node)[top.key];
    slot = std::move(value);
    return &slot;
  }

  // Path of `f`'s child being read; `pending`: that child is not placed in `f` yet.
  std::string child_path(const std::string& parent, const Frame& f, bool pending) const {
    if (f.node->is_array()) return json_path_index(parent, f.node->size() - (pending ? 0 : 1));
    return json_path_key(parent, f.key);
  }
  // Path of the innermost open container.
  std::string node_path() const {
    std::string path;
    for (std::size_t i = 0; i + 1 < stack_.size(); ++i) path = child_path(path, stack_[i], false);
    return path;
  }
  // Path of the value the parser was about to deliver.
  std::string pending_path() const {
    if (stack_.empty()) return {};
    return child_path(node_path(), stack_.back(), true);
  }

  // nlohmann reports the count of bytes read, so the offending byte is position - 1.
  std::pair<std::size_t, std::size_t> line_and_column(std::size_t position) const {
    const std::size_t at = std::min(position > 0 ? position - 1 : 0, text_.size());
    const auto begin = text_.begin();
    const auto line =
        1 + static_cast<std::size_t>(std::count(begin, begin + static_cast<std::ptrdiff_t>(at), '\n'));
    const std::size_t last_newline = at > 0 ? text_.rfind('\n', at - 1) : std::string::npos;
    return {line, last_newline == std::string::npos ? at + 1 : at - last_newline};
  }

  // "[json.exception.parse_error.101] parse error at line 3, column 14: syntax error while
  // parsing value - unexpected ','" -> "unexpected ','": the place is already in our prefix.
  static std::string syntax_detail(const std::string& what) {
    std::string detail = what;
    if (const auto col = detail.find("column "); col != std::string::npos) {
      if (const auto colon = detail.find(": ", col); colon != std::string::npos) {
        detail = detail.substr(colon + 2);
      }
    }
    if (detail.rfind("syntax error while parsing", 0) == 0) {
      if (const auto dash = detail.find(" - "); dash != std::string::npos) {
        detail = detail.substr(dash + 3);
      }
    }
    return detail;
  }

  const std::string& text_;
  const std::string& file_;
  Json root_;
  std::vector<Frame> stack_;
};

std::string describe_range_violation(const NumberRange& range, double v, bool* violated) {
  *violated = true;
  if (range.min && (range.min_exclusive ? !(v > *range.min) : !(v >= *range.min))) {
    return fmt::format("{} {}", range.min_exclusive ? ">" : ">=", *range.min);
  }
  if (range.max && (range.max_exclusive ? !(v < *range.max) : !(v <= *range.max))) {
    return fmt::format("{} {}", range.max_exclusive ? "<" : "<=", *range.max);
  }
  *violated = false;
  return {};
}

// JsonValue::real's checks of `v`, failing at `at` (a JsonValue or a JsonPlace); `shown` is the
// number as the message shows it.
template <typename Place>
float real_at(const Place& at, double v, const Json& shown, const NumberRange& range) {
  if (!std::isfinite(v)) at.fail(fmt::format("expected a finite number, got {}", describe_json(shown)));
  if (std::fabs(v) > static_cast<double>(std::numeric_limits<float>::max())) {
    at.fail(fmt::format("number {} is out of range for a 32-bit float", shown.dump()));
  }
  const auto f = static_cast<float>(v);
  // Checked after rounding, so 1e-50 cannot pass "> 0" and then be stored as 0.
  bool violated = false;
  const std::string bound = describe_range_violation(range, static_cast<double>(f), &violated);
  if (violated) at.fail(fmt::format("expected a number {}, got {}", bound, shown.dump()));
  return f;
}

}  // namespace

Json parse_json_strict(const std::string& text, const std::string& file) {
  StrictDomBuilder builder(text, file);
  if (!Json::sax_parse(text, &builder)) {
    throw InputError(fmt::format("{}: JSON syntax error", file));  // the builder throws first
  }
  return builder.take();
}

std::string json_path_key(const std::string& parent, std::string_view key) {
  if (is_identifier(key)) return parent.empty() ? std::string(key) : fmt::format("{}.{}", parent, key);
  const std::string quoted = Json(utf8_prefix(std::string(key), kMaxShownChars)).dump();
  return fmt::format("{}[{}]", parent, quoted);
}

std::string json_path_index(const std::string& parent, std::size_t index) {
  return fmt::format("{}[{}]", parent, index);
}

std::string join_alternatives(const std::vector<std::string_view>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += (i + 1 == names.size()) ? " or " : ", ";
    out += names[i];
  }
  return out;
}

std::string describe_json(const Json& value) {
  switch (value.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::boolean: return fmt::format("a boolean ({})", value.dump());
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float: return value.dump();
    case Json::value_t::string: {
      const auto& s = value.get_ref<const std::string&>();
      const std::string shown = Json(utf8_prefix(s, kMaxShownChars)).dump();
      return fmt::format("a string ({}{})", shown, s.size() > kMaxShownChars ? "..." : "");
    }
    case Json::value_t::array: return fmt::format("an array of {}", value.size());
    case Json::value_t::object: return "an object";
    default: return value.type_name();
  }
}

void JsonValue::fail(std::string_view what) const { throw_at(*file_, path_, what); }

void JsonPlace::fail(std::string_view what) const { throw_at(file, path, what); }

float JsonPlace::real(double v, const NumberRange& range) const { return real_at(*this, v, Json(v), range); }

glm::vec3 JsonPlace::vec3(const double (&v)[3], const NumberRange& range) const {
  glm::vec3 out;
  for (std::size_t i = 0; i < 3; ++i) out[static_cast<glm::length_t>(i)] = index(i).real(v[i], range);
  return out;
}

void JsonValue::fail_expected(std::string_view expected) const {
  fail(fmt::format("expected {}, got {}", expected, describe_json(*value_)));
}

float JsonValue::real(const NumberRange& range) const {
  if (!value_->is_number()) fail_expected("a number");
  return real_at(*this, value_->get<double>(), *value_, range);
}

std::int64_t JsonValue::integer(std::int64_t min, std::int64_t max) const {
  if (!value_->is_number()) fail_expected("an integer");
  auto below = [&] { fail(fmt::format("expected an integer >= {}, got {}", min, value_->dump())); };
  auto above = [&] { fail(fmt::format("expected an integer <= {}, got {}", max, value_->dump())); };
  if (value_->is_number_unsigned()) {
    const auto u = value_->get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) above();
    const auto v = static_cast<std::int64_t>(u);
    if (v < min) below();
    if (v > max) above();
    return v;
  }
  if (value_->is_number_integer()) {
    const auto v = value_->get<std::int64_t>();
    if (v < min) below();
    if (v > max) above();
    return v;
  }
  // A float literal such as 1e3 is accepted when it is integral and in range.
  const double d = value_->get<double>();
  if (!std::isfinite(d) || std::trunc(d) != d) fail_expected("an integer");
  constexpr double kTwo63 = 9223372036854775808.0;
  if (d < -kTwo63 || d < static_cast<double>(min)) below();
  if (d >= kTwo63 || d > static_cast<double>(max)) above();
  const auto v = static_cast<std::int64_t>(d);
  if (v < min) below();  // min/max may not be exact as doubles
  if (v > max) above();
  return v;
}

int JsonValue::int32(int min, int max) const { return static_cast<int>(integer(min, max)); }

std::uint64_t JsonValue::unsigned_integer() const {
  if (value_->is_number_unsigned()) return value_->get<std::uint64_t>();
  if (value_->is_number_float()) {
    const double d = value_->get<double>();
    if (std::isfinite(d) && std::trunc(d) == d && d >= 0.0 && d < 18446744073709551616.0) {
      return static_cast<std::uint64_t>(d);
    }
  }
  fail_expected("an unsigned integer");
}

bool JsonValue::boolean() const {
  if (!value_->is_boolean()) fail_expected("true or false");
  return value_->get<bool>();
}

std::string JsonValue::string() const {
  if (!value_->is_string()) fail_expected("a string");
  return value_->get<std::string>();
}

glm::vec3 JsonValue::vec3(const NumberRange& range) const {
  if (!value_->is_array() || value_->size() != 3) fail_expected("3 numbers");
  glm::vec3 out;
  for (std::size_t i = 0; i < 3; ++i) {
    out[static_cast<glm::length_t>(i)] =
        JsonValue((*value_)[i], json_path_index(path_, i), *file_).real(range);
  }
  return out;
}

std::vector<JsonValue> JsonValue::array() const {
  if (!value_->is_array()) fail_expected("an array");
  std::vector<JsonValue> out;
  out.reserve(value_->size());
  for (std::size_t i = 0; i < value_->size(); ++i) {
    out.emplace_back((*value_)[i], json_path_index(path_, i), *file_);
  }
  return out;
}

JsonObject JsonValue::object(std::initializer_list<std::string_view> allowed) const {
  return object(std::vector<std::string_view>(allowed));
}

JsonObject JsonValue::object(std::vector<std::string_view> allowed) const {
  JsonObject obj(*this, std::move(allowed));
  obj.reject_unknown_keys();
  return obj;
}

JsonObject::JsonObject(const JsonValue& value, std::initializer_list<std::string_view> allowed)
    : JsonObject(value, std::vector<std::string_view>(allowed)) {}

JsonObject::JsonObject(const JsonValue& value, std::vector<std::string_view> allowed)
    : value_(value), allowed_(std::move(allowed)) {
  if (!value_.raw().is_object()) value_.fail_expected("an object");
}

std::optional<JsonValue> JsonObject::get(std::string_view key) const {
  if (std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end()) {
    throw std::logic_error(fmt::format("JsonObject::get: '{}' is not an allowed key", key));
  }
  const auto& obj = value_.raw();
  const auto it = obj.find(key);
  if (it == obj.end()) return std::nullopt;
  return JsonValue(*it, json_path_key(value_.path(), key), value_.file());
}

JsonValue JsonObject::require(std::string_view key) const {
  if (auto v = get(key)) return *v;
  throw_at(value_.file(), json_path_key(value_.path(), key), "required key is missing");
}

void JsonObject::reject_unknown_keys() const {
  for (const auto& [key, child] : value_.raw().items()) {
    if (std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end()) {
      JsonValue(child, json_path_key(value_.path(), key), value_.file())
          .fail(fmt::format("unknown key (expected {})", join_alternatives(allowed_)));
    }
  }
}

}  // namespace farm
