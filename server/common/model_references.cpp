#include "server/common/model_references.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>

#include "renderer/util/file_extension.h"
#include "server/common/collada_images.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

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

// OBJ: `mtllib a.mtl [b.mtl ...]`, the names as written.
std::vector<std::string> obj_material_libraries(const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  std::vector<std::string> libraries;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key != "mtllib") continue;
    std::string name;
    while (words >> name) libraries.push_back(name);
  }
  return libraries;
}

// glTF: the uris of buffers and images.
void gltf_json_uris(const std::string& json_text, std::vector<std::string>& out) {
  const nlohmann::json doc = nlohmann::json::parse(json_text, nullptr, false);
  if (!doc.is_object()) return;  // the loader reports the syntax error with its position
  for (const char* key : {"buffers", "images"}) {
    if (!doc.contains(key) || !doc[key].is_array()) continue;
    for (const auto& item : doc[key]) {
      if (item.is_object() && item.contains("uri") && item["uri"].is_string()) {
        out.push_back(item["uri"].get<std::string>());
      }
    }
  }
}

// GLB: a 12-byte header, then chunks; the first is the JSON.
void glb_uris(const std::string& bytes, std::vector<std::string>& out) {
  if (bytes.size() < 20) return;
  std::uint32_t length = 0, type = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  std::memcpy(&type, bytes.data() + 16, 4);
  if (type != 0x4E4F534Au || 20 + static_cast<std::size_t>(length) > bytes.size()) return;  // "JSON"
  gltf_json_uris(bytes.substr(20, length), out);
}

void sort_unique(std::vector<fs::path>& files) {
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());
}

}  // namespace

std::vector<std::string> model_references(const fs::path& model, const std::string& bytes) {
  const std::string ext = lowercase_extension(model);
  std::vector<std::string> out;
  if (ext == ".obj") {
    out = obj_material_libraries(bytes);
  } else if (ext == ".gltf") {
    gltf_json_uris(bytes, out);
  } else if (ext == ".glb") {
    glb_uris(bytes, out);
  } else if (ext == ".dae") {
    out = collada_image_uris(bytes);
  }
  return out;
}

std::vector<std::string> material_library_maps(const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  std::vector<std::string> out;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string key, word, last;
    words >> key;
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
    if (key.rfind("map_", 0) != 0 && key != "bump" && key != "disp" && key != "decal" && key != "refl") continue;
    while (words >> word) last = word;
    out.push_back(last);
  }
  return out;
}

std::optional<std::string> local_reference(std::string written) {
  written = trim(written);
  if (written.empty() || written.rfind("data:", 0) == 0) return std::nullopt;
  if (written.rfind("file://", 0) == 0) written = written.substr(7);
  if (written.find("://") != std::string::npos) return std::nullopt;  // http and the like: never fetched
  std::replace(written.begin(), written.end(), '\\', '/');
  return percent_decode(written);
}

ModelReferenceScanner::Files ModelReferenceScanner::locate_each(const fs::path& model, const fs::path& referrer,
                                                               std::vector<std::string> written) {
  Files files;
  for (std::string& reference : written) {
    const std::optional<std::string> local = local_reference(reference);
    if (!local) continue;
    if (auto file = source_.locate(model, referrer, ModelReference{std::move(reference), *local})) {
      files.push_back(std::move(*file));
    }
  }
  return files;
}

std::optional<std::string> ModelReferenceScanner::read(const fs::path& file, const char* what) {
  std::optional<std::string> bytes = source_.read(file, what);
  if (bytes) ++files_scanned_;
  return bytes;
}

const ModelReferenceScanner::Files& ModelReferenceScanner::references(const fs::path& model) {
  const fs::path key = model.lexically_normal();
  if (const auto found = models_.find(key); found != models_.end()) return found->second;
  partial_.clear();
  std::vector<std::string> named;
  {
    const std::optional<std::string> bytes = read(key, "model file");
    if (!bytes) return partial_;
    named = model_references(key, *bytes);
  }  // the model's bytes freed before its libraries are read: one file held at a time
  const bool obj = lowercase_extension(key) == ".obj";
  Files found = locate_each(key, key, std::move(named));
  // An OBJ's libraries name its maps; one not to be had leaves the model to be scanned again.
  bool whole = true;
  if (obj) {
    const std::size_t libraries = found.size();
    for (std::size_t i = 0; i < libraries; ++i) {
      const fs::path library = found[i];
      if (const Files* maps = library_maps(key, library)) {
        found.insert(found.end(), maps->begin(), maps->end());
      } else {
        whole = false;
      }
    }
  }
  sort_unique(found);
  std::erase(found, key);
  // Remembered only once scanned whole: a file that could not be read is not remembered as
  // naming nothing.
  if (!whole) {
    partial_ = std::move(found);
    return partial_;
  }
  return models_.emplace(key, std::move(found)).first->second;
}

const ModelReferenceScanner::Files* ModelReferenceScanner::library_maps(const fs::path& model, const fs::path& library) {
  if (const auto found = libraries_.find(library); found != libraries_.end()) return &found->second;
  std::vector<std::string> names;
  {
    const std::optional<std::string> bytes = read(library, "material library");
    if (!bytes) return nullptr;
    names = material_library_maps(*bytes);
  }
  return &libraries_.emplace(library, locate_each(model, library, std::move(names))).first->second;
}

}  // namespace farm
