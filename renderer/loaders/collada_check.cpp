#include "renderer/loaders/collada_check.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>
#include <pugixml.hpp>

#include "renderer/loaders/token_count.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

// The line of `offset` in `text`, for messages.
std::size_t line_of(std::string_view text, std::ptrdiff_t offset) {
  const auto end = text.begin() + std::clamp<std::ptrdiff_t>(offset, 0, static_cast<std::ptrdiff_t>(text.size()));
  return static_cast<std::size_t>(std::count(text.begin(), end, '\n')) + 1;
}

class ColladaCheck {
 public:
  ColladaCheck(std::string_view text, const std::string& file) : text_(text), file_(file) {}

  void run() {
    pugi::xml_document doc;
    const pugi::xml_parse_result parsed = doc.load_buffer(text_.data(), text_.size());
    if (!parsed) {
      fail_at(parsed.offset, std::string("not well-formed XML: ") + parsed.description());
    }
    // Depth-first with an explicit stack: a hostile file cannot exhaust the call stack.
    std::vector<pugi::xml_node> stack{doc.document_element()};
    std::vector<pugi::xml_node> accessors;
    while (!stack.empty()) {
      const pugi::xml_node node = stack.back();
      stack.pop_back();
      check(node);
      if (named(node, {"accessor"})) accessors.push_back(node);
      for (pugi::xml_node child = node.last_child(); child; child = child.previous_sibling()) {
        if (child.type() == pugi::node_element) stack.push_back(child);
      }
    }
    for (const pugi::xml_node& accessor : accessors) check_accessor(accessor);
  }

 private:
  [[noreturn]] void fail_at(std::ptrdiff_t offset, const std::string& what) const {
    throw InputError(file_ + ":" + std::to_string(line_of(text_, offset)) + ": " + what);
  }
  [[noreturn]] void fail(const pugi::xml_node& node, const std::string& what) const {
    fail_at(node.offset_debug(), "<" + std::string(node.name()) + ">: " + what);
  }

  static bool named(const pugi::xml_node& node, std::initializer_list<std::string_view> names) {
    const std::string_view name = node.name();
    return std::find(names.begin(), names.end(), name) != names.end();
  }

  std::uint64_t count_attribute(const pugi::xml_node& node) const {
    return whole_number_attribute(node, "count", 0);
  }

  // The integers of an index list, in one pass over it; throws naming the first character that
  // is not a digit or a space. A primitive's lists are counted as part of it, and not again when
  // the walk reaches them (a mesh's <p> is most of its file: the bunny's was read four times).
  std::uint64_t index_count(const pugi::xml_node& node) {
    counted_.insert(node.internal_object());
    const std::string_view text = node.child_value();
    const Tokens tokens = count_tokens(text, true);
    if (tokens.bad < text.size()) {
      fail(node, std::string("'") + text[tokens.bad] + "' in an index list (only whole numbers >= 0)");
    }
    return tokens.count;
  }

  std::uint64_t whole_number_attribute(const pugi::xml_node& node, const char* name,
                                       std::uint64_t absent) const {
    const pugi::xml_attribute a = node.attribute(name);
    if (!a) return absent;
    const std::string_view value = a.value();
    std::uint64_t n = 0;
    const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), n);
    if (ec != std::errc() || end != value.data() + value.size()) {
      fail(node, std::string(name) + " \"" + std::string(value.substr(0, 40)) + "\" is not a whole number");
    }
    return n;
  }

  // Assimp reads an accessor's values at offset + stride * i + k for i below its count, and
  // checks i against the count but never the reach against the array: an accessor reaching past
  // its array (an empty one: past nothing at all) is read out of bounds, and crashed the process.
  void check_accessor(const pugi::xml_node& accessor) {
    const std::string_view source = accessor.attribute("source").value();
    if (source.size() < 2 || source[0] != '#') return;  // not a local array: Assimp refuses it
    const auto it = arrays_.find(std::string(source.substr(1)));
    if (it == arrays_.end()) return;  // unresolved: Assimp refuses it
    const std::uint64_t count = whole_number_attribute(accessor, "count", 0);
    const std::uint64_t stride = whole_number_attribute(accessor, "stride", 1);
    const std::uint64_t offset = whole_number_attribute(accessor, "offset", 0);
    if (count == 0) return;
    std::uint64_t params = 0;
    for (const pugi::xml_node param : accessor.children("param")) {
      (void)param;
      ++params;
    }
    // The values one element takes: its params (at least one).
    const std::uint64_t width = std::max<std::uint64_t>(params, 1);
    const std::uint64_t values = it->second;
    // Each term is checked against `values` (at most the file's size) before it is added or
    // multiplied, so nothing below wraps around.
    const std::uint64_t last = count - 1;
    const bool fits = offset <= values && stride <= values && width <= values - offset &&
                      (stride == 0 || last <= (values - offset - width) / stride);
    if (!fits) {
      fail(accessor, "count " + std::to_string(count) + ", stride " + std::to_string(stride) +
                         " and offset " + std::to_string(offset) + " reach past the " +
                         std::to_string(values) + " values of '" + it->first + "'");
    }
  }

  void check(const pugi::xml_node& node) {
    if (named(node, {"p", "v", "vcount", "h"})) {
      if (!counted_.contains(node.internal_object())) (void)index_count(node);
    } else if (named(node, {"float_array", "int_array", "bool_array", "Name_array", "IDREF_array"})) {
      const std::uint64_t count = count_attribute(node);
      const std::uint64_t values = count_tokens(node.child_value(), false).count;
      if (count > values) {
        fail(node, "count " + std::to_string(count) + " but " + std::to_string(values) + " values");
      }
      // Ids are unique in a COLLADA document (xs:ID). With two arrays of one id, an accessor could
      // be checked against one and read by Assimp from the other (an empty one: a SEGV found by
      // Fuzz.Run.collada_loader), so the second is refused.
      if (const std::string_view id = node.attribute("id").value(); !id.empty()) {
        if (!arrays_.emplace(std::string(id), count).second) {
          fail(node, "a second array with id '" + std::string(id.substr(0, 64)) + "' (ids must be unique)");
        }
      }
    } else if (named(node, {"triangles", "polylist", "polygons", "lines", "linestrips", "trifans",
                            "tristrips"})) {
      const std::uint64_t count = count_attribute(node);
      std::uint64_t numbers = 0, p_numbers = 0;
      for (const pugi::xml_node child : node.children()) {
        if (named(child, {"p", "vcount", "ph"})) {
          const std::uint64_t n = index_count(child);
          numbers += n;
          if (named(child, {"p"})) p_numbers += n;
        }
        // <polygons><ph><p>..</p><h>..</h></ph>: polygons with holes.
        if (named(child, {"ph"})) {
          for (const pugi::xml_node part : child.children()) {
            if (named(part, {"p", "h"})) numbers += index_count(part);
          }
        }
      }
      if (count > numbers) {
        fail(node, "count " + std::to_string(count) + " but " + std::to_string(numbers) +
                       " indices for them");
      }
      // A polylist's <vcount> gives each polygon's corners, and every corner takes at least one
      // index of its <p>: Assimp reserves their sum times its inputs before reading <p>, so a
      // vcount of 33333333333333333333 in a 10 kB file asked for 22.9 GB (found by the fuzzer).
      if (named(node, {"polylist"})) {
        const pugi::xml_node vcount = node.child("vcount");
        const std::uint64_t corners = vcount ? sum_of_whole_numbers(vcount.child_value()) : 0;
        if (corners > p_numbers) {
          fail(vcount, "polygons of " + (corners == UINT64_MAX ? std::string("more than 2^64") : std::to_string(corners)) +
                           " corners in all but " + std::to_string(p_numbers) + " indices in <p>");
        }
      }
    }
  }

  // The sum of an index list's whole numbers (its characters checked by index_count), held at
  // UINT64_MAX rather than wrapping.
  static std::uint64_t sum_of_whole_numbers(std::string_view text) {
    std::uint64_t sum = 0, value = 0;
    bool in_number = false;
    const auto add = [&] {
      sum = value > UINT64_MAX - sum ? UINT64_MAX : sum + value;
      value = 0;
      in_number = false;
    };
    for (const char c : text) {
      if (c >= '0' && c <= '9') {
        const auto digit = static_cast<std::uint64_t>(c - '0');
        value = value > (UINT64_MAX - digit) / 10 ? UINT64_MAX : value * 10 + digit;
        in_number = true;
      } else if (in_number) {
        add();
      }
    }
    if (in_number) add();
    return sum;
  }

  std::string_view text_;
  const std::string& file_;
  std::map<std::string, std::uint64_t> arrays_;  // by id: the values Assimp reads of each
  std::unordered_set<const pugi::xml_node_struct*> counted_;  // index lists checked already
};

}  // namespace

void check_collada_text(std::string_view text, const std::string& file) { ColladaCheck(text, file).run(); }

void check_collada_file(const ConfinedFile& file, const std::string& name) {
  std::string text;
  std::string why;
  if (!read_confined(file, text, &why)) throw InputError(name + ": " + why);
  check_collada_text(text, name);
}

}  // namespace farm
