#include "server/client/model_dependencies.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "renderer/util/file_extension.h"
#include "renderer/util/input_error.h"
#include "server/client/collada_images.h"

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

// MTL: map_Kd, bump, disp, ... whose last word is the file.
std::vector<std::string> mtl_maps(const std::string& text) {
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

void sort_unique(std::vector<ConfinedFile>& files) {
  const auto by_name = [](const ConfinedFile& a, const ConfinedFile& b) { return a.named < b.named; };
  std::sort(files.begin(), files.end(), by_name);
  files.erase(std::unique(files.begin(), files.end(),
                          [](const ConfinedFile& a, const ConfinedFile& b) { return a.named == b.named; }),
              files.end());
}

}  // namespace

ModelDependencyScanner::ModelDependencyScanner(fs::path asset_root)
    : root_(fs::weakly_canonical(fs::absolute(asset_root))) {}

std::optional<ConfinedFile> ModelDependencyScanner::reference(const fs::path& model, const fs::path& referrer,
                                                              std::string written) const {
  written = trim(written);
  if (written.empty() || written.rfind("data:", 0) == 0) return std::nullopt;
  if (written.rfind("file://", 0) == 0) written = written.substr(7);
  if (written.find("://") != std::string::npos) return std::nullopt;  // http and the like: never fetched
  std::replace(written.begin(), written.end(), '\\', '/');
  ConfinedFile file = confine_file(root_, referrer, percent_decode(written));
  if (file.allowed()) return file;
  if (file.verdict == Confinement::missing) return std::nullopt;
  // Named by the model, or by a material library the model names.
  std::string message = referrer == model ? file.message : model.string() + ": " + file.message;
  if (file.verdict == Confinement::outside) message += " (give --asset-root a folder that holds both)";
  throw InputError(message);
}

const std::vector<ConfinedFile>& ModelDependencyScanner::dependencies(const fs::path& model) {
  const fs::path key = model.lexically_normal();
  if (const auto found = models_.find(key); found != models_.end()) return found->second;
  // Stored only once the scan succeeded: a file that could not be read is not remembered as
  // having no dependencies.
  Files found = scan_model(key);
  sort_unique(found);
  std::erase_if(found, [&](const ConfinedFile& f) { return f.named == key; });
  return models_.emplace(key, std::move(found)).first->second;
}

std::string ModelDependencyScanner::read(const ConfinedFile& file, const char* what) {
  std::string bytes, why;
  if (!read_confined(file, bytes, &why)) {
    throw InputError(fmt::format("{}: cannot read the {}: {}", file.named.string(), what, why));
  }
  ++files_scanned_;
  return bytes;
}

ModelDependencyScanner::Files ModelDependencyScanner::scan_model(const fs::path& model) {
  // The model itself, as the job named it (job paths may be absolute).
  const ConfinedFile self = confine_file(root_, model, model.string(), ReferenceForm::relative_or_absolute);
  if (self.verdict == Confinement::missing) throw InputError(model.string() + ": cannot read the model file");
  if (!self.allowed()) throw InputError(model.string() + ": " + self.reason);
  const std::string ext = lowercase_extension(model);
  if (ext == ".obj") return scan_obj(model, read(self, "model file"));
  std::vector<std::string> uris;
  if (ext == ".gltf") {
    gltf_json_uris(read(self, "model file"), uris);
  } else if (ext == ".glb") {
    glb_uris(read(self, "model file"), uris);
  } else if (ext == ".dae") {
    uris = collada_image_uris(read(self, "model file"));
  }
  Files out;
  for (const std::string& uri : uris) {
    if (auto file = reference(model, model, uri)) out.push_back(std::move(*file));
  }
  return out;
}

ModelDependencyScanner::Files ModelDependencyScanner::scan_obj(const fs::path& model, const std::string& text) {
  Files out;
  for (const std::string& name : obj_material_libraries(text)) {
    if (auto library = reference(model, model, name)) out.push_back(std::move(*library));
  }
  const std::size_t libraries = out.size();
  for (std::size_t i = 0; i < libraries; ++i) {
    const Files& maps = material_library_maps(model, ConfinedFile(out[i]));
    out.insert(out.end(), maps.begin(), maps.end());
  }
  return out;
}

const ModelDependencyScanner::Files& ModelDependencyScanner::material_library_maps(const fs::path& model,
                                                                                  const ConfinedFile& library) {
  if (const auto found = material_libraries_.find(library.named); found != material_libraries_.end()) {
    return found->second;
  }
  Files maps;
  for (const std::string& name : mtl_maps(read(library, "material library"))) {
    if (auto map = reference(model, library.named, name)) maps.push_back(std::move(*map));
  }
  return material_libraries_.emplace(library.named, std::move(maps)).first->second;
}

std::vector<ConfinedFile> model_dependencies(const fs::path& model) {
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(fs::absolute(model), ec);
  ModelDependencyScanner scanner(resolved.parent_path());
  return scanner.dependencies(resolved);
}

}  // namespace farm
