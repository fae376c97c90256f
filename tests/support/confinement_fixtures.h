#pragma once
// What the confinement tests of every component share (client, scheduler, worker, loaders): models
// that name one file, the ways a name can try to leave the asset root, a secret outside the root
// whose content must never turn up, and a guard that releases a reader stuck on a FIFO so that a
// test always finishes (and then fails on what the reader did, never on how long it took).
#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/temp_dir.h"

namespace farm::test {

// In the secret's material name: had the secret been read, this would turn up somewhere.
inline constexpr const char* kSecretMarker = "SECRET_MATERIAL_7f3a";

// A red material library: what a model reaching outside its root would get.
std::string secret_mtl();
// One triangle using material `m` from the library named `mtllib`.
std::string triangle_obj(const std::string& mtllib);
// One triangle in glTF: positions in the external buffer `buffer_uri` (triangle_bin's 36 bytes),
// and an image named by `image_uri` when it is not empty.
std::string triangle_gltf(const std::string& buffer_uri, const std::string& image_uri = "");
std::string triangle_bin();
// A harmless material library and a harmless image, for the references that are allowed.
std::string plain_mtl();

// How a model's reference tries to reach what it may not.
enum class Escape {
  dot_dot,      // "../../elsewhere/secret.mtl": out of the root by `..`
  absolute,     // "/.../elsewhere/secret.mtl"
  symlink_out,  // "link.mtl", a link in the model's folder to the secret
  fifo,         // "pipe.mtl", a FIFO in the model's folder
  directory,    // "folder.mtl", a directory in the model's folder
};
inline constexpr Escape kAllEscapes[] = {Escape::dot_dot, Escape::absolute, Escape::symlink_out, Escape::fifo,
                                         Escape::directory};
const char* to_string(Escape escape);

// Which reference of which model tries to escape, and the cases every component is tried with.
enum class ModelReference { obj_mtllib, gltf_buffer, gltf_image };
const char* to_string(ModelReference reference);
struct ConfinementCase {
  ModelReference reference;
  Escape escape;
};
std::vector<ConfinementCase> all_confinement_cases();  // every reference with every escape
// "ObjMtllib_DotDot": the name of a parameterized test's case.
std::string confinement_case_name(const ::testing::TestParamInfo<ConfinementCase>& info);

// The files of a job of one model whose `kind` reference is `reference` (a glTF's other reference
// is its own tri.bin), written under `dir`/files: (path in the job, file on disk), the model first.
struct CraftedModel {
  std::string model;  // "tri.obj" or "tri.gltf"
  std::vector<std::pair<std::string, std::filesystem::path>> files;
};
CraftedModel craft_model(const TempDir& dir, ModelReference kind, const std::string& reference);

// A server's copy of a job (its `scene` folder, laid out from `files`) with the link or FIFO that
// `escape` needs placed in it beforehand: a spec cannot carry those. Returns what a read through
// the escape would open (the secret, or the FIFO) and the FIFOs to release.
struct PlacedEscape {
  std::filesystem::path target;
  std::vector<std::filesystem::path> fifos;
};
PlacedEscape place_escape_in_scene(Escape escape, const std::filesystem::path& scene,
                                   const std::vector<std::pair<std::string, std::filesystem::path>>& files,
                                   const std::filesystem::path& secret, const std::string& name);

// Makes what `escape` needs and returns the reference a model in `model_dir` writes for it: the
// secret (secret_mtl) at `secret`, outside the root, `..` components enough to climb from
// `model_dir` to `secret`'s folder, a link, a FIFO or a folder named `name` in `model_dir`.
std::string make_escape(Escape escape, const std::filesystem::path& model_dir, const std::filesystem::path& secret,
                        const std::string& name);

// Reports whether anything opened a file (inotify IN_OPEN, any process) since the watch began:
// "nothing was read" made observable. Lists, stats and links resolved along a path do not count.
class OpenWatch {
 public:
  explicit OpenWatch(const std::filesystem::path& file);
  ~OpenWatch();
  OpenWatch(const OpenWatch&) = delete;
  OpenWatch& operator=(const OpenWatch&) = delete;
  bool watching() const { return fd_ >= 0 && watch_ >= 0; }
  bool opened();  // true once an open has been seen

 private:
  int fd_ = -1;
  int watch_ = -1;
  bool opened_ = false;
};

// What a reference made by make_escape would open: the FIFO or the folder it names, else the secret.
std::filesystem::path escape_target(Escape escape, const std::filesystem::path& model_dir,
                                    const std::filesystem::path& secret, const std::string& name);

// While alive, and once `grace` has passed, opens each FIFO for writing now and then and closes it
// again: a reader blocked in open() on one then reads an empty file and carries on.
class FifoReleaser {
 public:
  explicit FifoReleaser(std::vector<std::filesystem::path> fifos,
                        std::chrono::seconds grace = std::chrono::seconds(30));
  ~FifoReleaser();
  FifoReleaser(const FifoReleaser&) = delete;
  FifoReleaser& operator=(const FifoReleaser&) = delete;
  // Whether a reader was found waiting on one of the FIFOs (and released).
  bool released_a_reader() const { return released_; }

 private:
  std::vector<std::filesystem::path> fifos_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> released_{false};
  std::thread thread_;
};

}  // namespace farm::test
