#include "renderer/texture/texture_cache.h"

#include <fmt/format.h>

#include <future>
#include <map>
#include <mutex>
#include <string>
#include <system_error>
#include <tuple>

#include "renderer/texture/height_map.h"

namespace farm {

namespace fs = std::filesystem;

// A file as decoded: where it is (and which of its embedded images: "" for the file itself), how
// big, when it changed, and how it was read.
using TextureKey = std::tuple<std::string, std::string, std::uintmax_t, std::int64_t, int>;

struct TextureCache::State {
  std::mutex mutex;
  std::map<TextureKey, std::weak_ptr<const Texture>> textures;
  // The decodes under way: a caller asking for one of these waits on its future, so a key is
  // decoded once however many ask at once, and a failure reaches every one of them.
  std::map<TextureKey, std::shared_future<std::shared_ptr<const Texture>>> decoding;
  std::uint64_t decodes = 0;
};

namespace {

// A file that cannot be looked at (missing, unreadable) keys by the path as given with size and
// time 0: its decode fails and is tried again by the next caller, as nothing is kept for it.
TextureKey key_of(const fs::path& file, const std::string& part, TextureColourSpace space) {
  std::error_code where_error, size_error, time_error;
  const fs::path where = fs::weakly_canonical(file, where_error);
  const std::uintmax_t size = fs::file_size(file, size_error);
  const fs::file_time_type changed = fs::last_write_time(file, time_error);
  const bool known = !size_error && !time_error;
  return {(where_error ? file : where).string(), part, known ? size : 0,
          known ? static_cast<std::int64_t>(changed.time_since_epoch().count()) : 0, static_cast<int>(space)};
}

}  // namespace

TextureCache::TextureCache() : state_(std::make_unique<State>()) {}
TextureCache::~TextureCache() = default;

std::shared_ptr<const Texture> TextureCache::get(const fs::path& file, TextureColourSpace space) {
  return get_or_decode(file, "", space, [&] { return load_texture_file(file, space); });
}

std::shared_ptr<const Texture> TextureCache::get_embedded(const fs::path& container, int index,
                                                          std::span<const unsigned char> encoded,
                                                          TextureColourSpace space) {
  const std::string name = fmt::format("{} image {}", container.string(), index);
  return get_or_decode(container, fmt::format("image {}", index), space,
                       [&] { return load_texture_bytes(encoded, name, space); });
}

std::shared_ptr<const Texture> TextureCache::get_normals_from_height(const fs::path& file, const Texture& height,
                                                                     float scale, TextureWrap wrap_u,
                                                                     TextureWrap wrap_v) {
  const std::string part = fmt::format("normals from height, scale {}, wrap {} {}", scale, static_cast<int>(wrap_u),
                                       static_cast<int>(wrap_v));
  return get_or_decode(file, part, TextureColourSpace::Linear,
                       [&] { return normal_map_from_height(height, scale, wrap_u, wrap_v); });
}

template <typename Decode>
std::shared_ptr<const Texture> TextureCache::get_or_decode(const fs::path& file, const std::string& part,
                                                           TextureColourSpace space, Decode&& decode) {
  const TextureKey key = key_of(file, part, space);
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  if (const auto it = s.textures.find(key); it != s.textures.end()) {
    if (std::shared_ptr<const Texture> live = it->second.lock()) return live;
  }
  if (const auto it = s.decoding.find(key); it != s.decoding.end()) {
    const std::shared_future<std::shared_ptr<const Texture>> pending = it->second;
    lock.unlock();
    return pending.get();  // the decoder's texture, or its exception rethrown
  }
  std::promise<std::shared_ptr<const Texture>> promise;
  s.decoding.emplace(key, promise.get_future().share());
  ++s.decodes;
  lock.unlock();

  std::shared_ptr<const Texture> texture;
  try {
    texture = decode();
  } catch (...) {
    // Nothing is kept for a failure: the waiters get this exception, the next caller decodes anew.
    lock.lock();
    s.decoding.erase(key);
    lock.unlock();
    promise.set_exception(std::current_exception());
    throw;
  }
  lock.lock();
  s.textures[key] = texture;
  s.decoding.erase(key);
  // Keys whose textures are gone are dropped as new ones come, so the map stays as large as what is held.
  std::erase_if(s.textures, [](const auto& entry) { return entry.second.expired(); });
  lock.unlock();
  promise.set_value(texture);
  return texture;
}

std::uint64_t TextureCache::decodes() const {
  std::lock_guard lock(state_->mutex);
  return state_->decodes;
}

TextureCache& TextureCache::process() {
  static TextureCache cache;
  return cache;
}

}  // namespace farm
