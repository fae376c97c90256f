#include "server/client/model_dependencies.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "server/client/collada_images.h"
#include "server/common/read_whole_file.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

std::string lower_extension(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::string trim(std::string s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

// %20 and friends in URIs (glTF, COLLADA); other characters are kept as they are.
std::string percent_decode(const std::string& uri) {
  std::string out;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      out += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// A reference as a file next to `model`, if it names a local file that exists.
void add_reference(const fs::path& model, std::string reference, std::vector<fs::path>& out) {
  reference = trim(reference);
  if (reference.empty() || reference.rfind("data:", 0) == 0) return;
  if (reference.rfind("file://", 0) == 0) reference = reference.substr(7);
  if (reference.find("://") != std::string::npos) return;  // http and the like: never fetched
  std::replace(reference.begin(), reference.end(), '\\', '/');
  const fs::path file = (model.parent_path() / percent_decode(reference)).lexically_normal();
  std::error_code ec;
  if (fs::is_regular_file(file, ec)) out.push_back(file);
}

// OBJ: `mtllib a.mtl [b.mtl ...]`; MTL: map_Kd, bump, disp, ... whose last word is the file.
void obj_dependencies(const fs::path& model, std::vector<fs::path>& out) {
  std::istringstream lines(read_whole_file(model, "model file"));
  std::string line;
  std::vector<fs::path> libraries;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key != "mtllib") continue;
    std::string name;
    while (words >> name) add_reference(model, name, libraries);
  }
  for (const fs::path& library : libraries) {
    out.push_back(library);
    std::istringstream mtl(read_whole_file(library, "material library"));
    while (std::getline(mtl, line)) {
      std::istringstream words(line);
      std::string key, word, last;
      words >> key;
      std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
      if (key.rfind("map_", 0) != 0 && key != "bump" && key != "disp" && key != "decal" && key != "refl") continue;
      while (words >> word) last = word;
      add_reference(library, last, out);
    }
  }
}

void gltf_json_dependencies(const fs::path& model, const std::string& json_text, std::vector<fs::path>& out) {
  const nlohmann::json doc = nlohmann::json::parse(json_text, nullptr, false);
  if (!doc.is_object()) return;  // the loader reports the syntax error with its position
  for (const char* key : {"buffers", "images"}) {
    if (!doc.contains(key) || !doc[key].is_array()) continue;
    for (const auto& item : doc[key]) {
      if (item.is_object() && item.contains("uri") && item["uri"].is_string()) {
        add_reference(model, item["uri"].get<std::string>(), out);
      }
    }
  }
}

// GLB: a 12-byte header, then chunks; the first is the JSON.
void glb_dependencies(const fs::path& model, std::vector<fs::path>& out) {
  const std::string bytes = read_whole_file(model, "model file");
  if (bytes.size() < 20) return;
  std::uint32_t length = 0, type = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  std::memcpy(&type, bytes.data() + 16, 4);
  if (type != 0x4E4F534Au || 20 + static_cast<std::size_t>(length) > bytes.size()) return;  // "JSON"
  gltf_json_dependencies(model, bytes.substr(20, length), out);
}

// COLLADA: the <image> elements' files, read as XML (collada_images.h).
void collada_dependencies(const fs::path& model, std::vector<fs::path>& out) {
  for (const std::string& uri : collada_image_uris(read_whole_file(model, "model file"))) {
    add_reference(model, uri, out);
  }
}

}  // namespace

std::vector<fs::path> model_dependencies(const fs::path& model) {
  std::vector<fs::path> out;
  const std::string ext = lower_extension(model);
  if (ext == ".obj") {
    obj_dependencies(model, out);
  } else if (ext == ".gltf") {
    gltf_json_dependencies(model, read_whole_file(model, "model file"), out);
  } else if (ext == ".glb") {
    glb_dependencies(model, out);
  } else if (ext == ".dae") {
    collada_dependencies(model, out);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  const fs::path self = model.lexically_normal();
  out.erase(std::remove(out.begin(), out.end(), self), out.end());
  return out;
}

}  // namespace farm
