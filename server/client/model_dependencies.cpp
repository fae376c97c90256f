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

// OBJ: `mtllib a.mtl [b.mtl ...]`.
std::vector<fs::path> obj_material_libraries(const fs::path& model, const std::string& text) {
  std::istringstream lines(text);
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
  return libraries;
}

// MTL: map_Kd, bump, disp, ... whose last word is the file.
std::vector<fs::path> mtl_maps(const fs::path& library, const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  std::vector<fs::path> out;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string key, word, last;
    words >> key;
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
    if (key.rfind("map_", 0) != 0 && key != "bump" && key != "disp" && key != "decal" && key != "refl") continue;
    while (words >> word) last = word;
    add_reference(library, last, out);
  }
  return out;
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
void glb_dependencies(const fs::path& model, const std::string& bytes, std::vector<fs::path>& out) {
  if (bytes.size() < 20) return;
  std::uint32_t length = 0, type = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  std::memcpy(&type, bytes.data() + 16, 4);
  if (type != 0x4E4F534Au || 20 + static_cast<std::size_t>(length) > bytes.size()) return;  // "JSON"
  gltf_json_dependencies(model, bytes.substr(20, length), out);
}

void sort_unique(std::vector<fs::path>& paths) {
  std::sort(paths.begin(), paths.end());
  paths.erase(std::unique(paths.begin(), paths.end()), paths.end());
}

}  // namespace

const std::vector<fs::path>& ModelDependencyScanner::dependencies(const fs::path& model) {
  const fs::path key = model.lexically_normal();
  if (const auto found = models_.find(key); found != models_.end()) return found->second;
  // Stored only once the scan succeeded: a file that could not be read is not remembered as
  // having no dependencies.
  Paths found = scan_model(key);
  sort_unique(found);
  found.erase(std::remove(found.begin(), found.end(), key), found.end());
  return models_.emplace(key, std::move(found)).first->second;
}

std::string ModelDependencyScanner::read(const fs::path& file, const char* what) {
  std::string bytes = read_whole_file(file, what);
  ++files_scanned_;
  return bytes;
}

ModelDependencyScanner::Paths ModelDependencyScanner::scan_model(const fs::path& model) {
  const std::string ext = lower_extension(model);
  Paths out;
  if (ext == ".obj") {
    out = scan_obj(model);
  } else if (ext == ".gltf") {
    gltf_json_dependencies(model, read(model, "model file"), out);
  } else if (ext == ".glb") {
    glb_dependencies(model, read(model, "model file"), out);
  } else if (ext == ".dae") {
    for (const std::string& uri : collada_image_uris(read(model, "model file"))) {
      add_reference(model, uri, out);
    }
  }
  return out;
}

ModelDependencyScanner::Paths ModelDependencyScanner::scan_obj(const fs::path& model) {
  Paths out = obj_material_libraries(model, read(model, "model file"));
  const std::size_t libraries = out.size();
  for (std::size_t i = 0; i < libraries; ++i) {
    const Paths& maps = material_library_maps(out[i]);
    out.insert(out.end(), maps.begin(), maps.end());
  }
  return out;
}

const ModelDependencyScanner::Paths& ModelDependencyScanner::material_library_maps(const fs::path& library) {
  if (const auto found = material_libraries_.find(library); found != material_libraries_.end()) {
    return found->second;
  }
  Paths maps = mtl_maps(library, read(library, "material library"));
  return material_libraries_.emplace(library, std::move(maps)).first->second;
}

std::vector<fs::path> model_dependencies(const fs::path& model) {
  ModelDependencyScanner scanner;
  return scanner.dependencies(model);
}

}  // namespace farm
