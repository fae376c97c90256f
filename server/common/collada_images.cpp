#include "server/common/collada_images.h"

#include <pugixml.hpp>

#include <string_view>

namespace farm {
namespace {

// COLLADA files are usually unprefixed in the default namespace, but an exporter may write
// <c:image>; pugixml does not resolve namespaces, so elements are matched by their local name.
std::string_view local_name(const pugi::xml_node& node) {
  const std::string_view name = node.name();
  const std::size_t colon = name.find(':');
  return colon == std::string_view::npos ? name : name.substr(colon + 1);
}

bool is_element(const pugi::xml_node& node, std::string_view name) {
  return node.type() == pugi::node_element && local_name(node) == name;
}

bool inside_image(pugi::xml_node node) {
  for (node = node.parent(); node; node = node.parent()) {
    if (is_element(node, "image")) return true;
  }
  return false;
}

// pugixml's traverse walks the tree without recursion, so a deeply nested hostile file cannot
// exhaust the stack here.
class ImageUriCollector : public pugi::xml_tree_walker {
 public:
  explicit ImageUriCollector(std::vector<std::string>& out) : out_(out) {}

  bool for_each(pugi::xml_node& node) override {
    if (!is_element(node, "init_from") || !inside_image(node)) return true;
    // 1.5: the URI is a <ref> child (a <hex> child holds pixels instead). 1.4: it is the text.
    bool has_children = false;
    for (const pugi::xml_node& child : node.children()) {
      if (child.type() != pugi::node_element) continue;
      has_children = true;
      if (local_name(child) == "ref") out_.emplace_back(child.text().get());
    }
    if (!has_children) out_.emplace_back(node.text().get());
    return true;
  }

 private:
  std::vector<std::string>& out_;
};

}  // namespace

std::vector<std::string> collada_image_uris(std::string xml) {
  pugi::xml_document doc;
  // Only what a URI can contain: entities (&amp;) and CDATA. Whitespace-only text, comments,
  // processing instructions and the DOCTYPE are skipped, which keeps the parse of a large mesh
  // (mostly <float_array> text) cheap.
  const unsigned options = pugi::parse_escapes | pugi::parse_cdata;
  if (!doc.load_buffer_inplace(xml.data(), xml.size(), options)) return {};
  std::vector<std::string> out;
  ImageUriCollector collector(out);
  doc.traverse(collector);
  return out;
}

}  // namespace farm
