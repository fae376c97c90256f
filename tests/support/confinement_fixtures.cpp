#include "tests/support/confinement_fixtures.h"

#include <fcntl.h>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace farm::test {

namespace fs = std::filesystem;

std::string secret_mtl() { return std::string("newmtl m\nKd 1 0 0\nKa 1 0 0\n# ") + kSecretMarker + "\n"; }

std::string plain_mtl() { return "newmtl m\nKd 0.2 0.8 0.2\n"; }

std::string triangle_obj(const std::string& mtllib) {
  return "mtllib " + mtllib + "\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";
}

std::string triangle_bin() {
  const float positions[9] = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
  return std::string(reinterpret_cast<const char*>(positions), sizeof positions);
}

std::string triangle_gltf(const std::string& buffer_uri, const std::string& image_uri) {
  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"},
         {"min", {-1, -1, 0}}, {"max", {1, 1, 0}}}}},
      {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}}},
      {"buffers", {{{"uri", buffer_uri}, {"byteLength", 36}}}},
  };
  if (!image_uri.empty()) doc["images"] = {{{"uri", image_uri}}};
  return doc.dump(1);
}

const char* to_string(Escape escape) {
  switch (escape) {
    case Escape::dot_dot: return "DotDot";
    case Escape::absolute: return "Absolute";
    case Escape::symlink_out: return "SymlinkOut";
    case Escape::fifo: return "Fifo";
    case Escape::directory: return "Directory";
  }
  return "?";
}

std::string make_escape(Escape escape, const fs::path& model_dir, const fs::path& secret, const std::string& name) {
  fs::create_directories(model_dir);
  fs::create_directories(secret.parent_path());
  std::ofstream(secret, std::ios::binary) << secret_mtl();
  switch (escape) {
    case Escape::dot_dot:
      // Climbs only by `..`, whatever the folders are called.
      return secret.lexically_relative(model_dir).generic_string();
    case Escape::absolute:
      return secret.generic_string();
    case Escape::symlink_out:
      fs::create_symlink(secret, model_dir / name);
      return name;
    case Escape::fifo:
      if (::mkfifo((model_dir / name).c_str(), 0600) != 0) {
        throw std::runtime_error("mkfifo " + (model_dir / name).string() + ": " + std::strerror(errno));
      }
      return name;
    case Escape::directory:
      fs::create_directories(model_dir / name);
      return name;
  }
  return name;
}

fs::path escape_target(Escape escape, const fs::path& model_dir, const fs::path& secret, const std::string& name) {
  return escape == Escape::fifo || escape == Escape::directory ? model_dir / name : secret;
}

OpenWatch::OpenWatch(const fs::path& file) : fd_(::inotify_init1(IN_NONBLOCK | IN_CLOEXEC)) {
  if (fd_ >= 0) watch_ = ::inotify_add_watch(fd_, file.c_str(), IN_OPEN);
}

OpenWatch::~OpenWatch() {
  if (fd_ >= 0) ::close(fd_);
}

bool OpenWatch::opened() {
  if (!watching()) return opened_;
  alignas(inotify_event) char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd_, buffer, sizeof buffer);
    if (n <= 0) break;
    for (ssize_t at = 0; at < n;) {
      const auto* event = reinterpret_cast<const inotify_event*>(buffer + at);
      if (event->mask & IN_OPEN) opened_ = true;
      at += static_cast<ssize_t>(sizeof(inotify_event) + event->len);
    }
  }
  return opened_;
}

FifoReleaser::FifoReleaser(std::vector<fs::path> fifos, std::chrono::seconds grace) : fifos_(std::move(fifos)) {
  thread_ = std::thread([this, grace] {
    const auto start = std::chrono::steady_clock::now();
    while (!stop_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (std::chrono::steady_clock::now() - start < grace) continue;
      for (const fs::path& fifo : fifos_) {
        // Succeeds only while a reader has it open (ENXIO otherwise).
        const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
        if (fd >= 0) {
          released_ = true;
          ::close(fd);
        }
      }
    }
  });
}

FifoReleaser::~FifoReleaser() {
  stop_ = true;
  thread_.join();
}

const char* to_string(ModelReference reference) {
  switch (reference) {
    case ModelReference::obj_mtllib: return "ObjMtllib";
    case ModelReference::gltf_buffer: return "GltfBuffer";
    case ModelReference::gltf_image: return "GltfImage";
  }
  return "?";
}

std::vector<ConfinementCase> all_confinement_cases() {
  std::vector<ConfinementCase> cases;
  for (ModelReference r : {ModelReference::obj_mtllib, ModelReference::gltf_buffer, ModelReference::gltf_image}) {
    for (Escape e : kAllEscapes) cases.push_back({r, e});
  }
  return cases;
}

std::string confinement_case_name(const ::testing::TestParamInfo<ConfinementCase>& info) {
  return std::string(to_string(info.param.reference)) + "_" + to_string(info.param.escape);
}

CraftedModel craft_model(const TempDir& dir, ModelReference kind, const std::string& reference) {
  CraftedModel m;
  if (kind == ModelReference::obj_mtllib) {
    m.model = "tri.obj";
    m.files.emplace_back(m.model, dir.write("files/tri.obj", triangle_obj(reference)));
  } else {
    m.model = "tri.gltf";
    m.files.emplace_back("tri.bin", dir.write("files/tri.bin", triangle_bin()));
    m.files.emplace_back(m.model, dir.write("files/tri.gltf", kind == ModelReference::gltf_buffer
                                                                  ? triangle_gltf(reference)
                                                                  : triangle_gltf("tri.bin", reference)));
  }
  return m;
}

PlacedEscape place_escape_in_scene(Escape escape, const std::filesystem::path& scene,
                                   const std::vector<std::pair<std::string, std::filesystem::path>>& files,
                                   const std::filesystem::path& secret, const std::string& name) {
  // The folder of the directory case appears only as the server lays the job out.
  PlacedEscape placed{secret, {}};
  if (escape == Escape::symlink_out || escape == Escape::fifo) {
    std::filesystem::create_directories(scene);
    for (const auto& [path, file] : files) std::filesystem::copy_file(file, scene / path);
    make_escape(escape, scene, secret, name);
  }
  if (escape == Escape::fifo) {
    placed.target = scene / name;
    placed.fifos.push_back(placed.target);
  }
  return placed;
}

}  // namespace farm::test
