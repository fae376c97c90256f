#pragma once
// Each texture file decoded once per process while anything holds it (docs/architecture.md,
// "Textures"): every model, object and frame of a job, and every job on a worker, naming the
// same file in the same colour space shares one Texture.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include "renderer/texture/texture_file.h"

namespace farm {

class TextureCache {
 public:
  // The texture of `file` read as `space`: decoded by the first caller, shared with every later
  // one while any of them holds it (weakly held: freed with its last user). A file changed since
  // (size or modification time) is decoded again. Callers asking for one file at once wait for
  // one decode. Throws what load_texture_file throws (and a later call tries again).
  std::shared_ptr<const Texture> get(const std::filesystem::path& file, TextureColourSpace space);

  // The same for image `index` embedded in `container` (a .glb's buffer, a data: URI), whose
  // bytes are `encoded`: keyed by the container file and the index, so that it too is decoded
  // once while held, and again when the container changes. Throws what load_texture_bytes throws.
  std::shared_ptr<const Texture> get_embedded(const std::filesystem::path& container, int index,
                                              std::span<const unsigned char> encoded, TextureColourSpace space);

  // The normal map made from the height map `file` (normal_map_from_height with these arguments),
  // kept as decoded textures are: made once while anything holds it. `height` is that file as
  // get(file, Linear) gives it, which the caller holds already.
  std::shared_ptr<const Texture> get_normals_from_height(const std::filesystem::path& file, const Texture& height,
                                                         float scale, TextureWrap wrap_u, TextureWrap wrap_v);

  // How many decodes this cache has begun (those that failed included): tests count with it.
  std::uint64_t decodes() const;

  // The process's cache, which the model loaders use.
  static TextureCache& process();

  TextureCache();
  ~TextureCache();
  TextureCache(const TextureCache&) = delete;
  TextureCache& operator=(const TextureCache&) = delete;

 private:
  struct State;
  template <typename Decode>
  std::shared_ptr<const Texture> get_or_decode(const std::filesystem::path& file, const std::string& part,
                                               TextureColourSpace space, Decode&& decode);
  std::unique_ptr<State> state_;
};

}  // namespace farm
