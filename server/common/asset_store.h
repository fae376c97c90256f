#pragma once
// Content-addressed blobs in one folder: an asset's bytes live in `<dir>/<sha256>`. A blob appears
// only complete and verified: it is written to a temporary file in the same folder, its SHA-256
// (and size, when known) checked, and then renamed into place, so a crash, a concurrent writer of
// the same blob or a lying peer never leaves a wrong or partial file under a hash's name.
#include <cstdint>
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "server/common/sha256.h"

namespace farm {

class AssetStore {
 public:
  // Creates `dir` if needed.
  explicit AssetStore(std::filesystem::path dir);

  const std::filesystem::path& dir() const { return dir_; }

  bool has(std::string_view sha256) const;
  // The blob is there and its bytes hash to its name (it is read whole: a disk or a hand may
  // have changed it since it was verified and published).
  bool intact(std::string_view sha256) const;
  // Removes the blob (a damaged one, so that it can be uploaded again); nothing if it is absent.
  void remove(std::string_view sha256) const;
  // Removes what uploads cut short left behind (a process killed mid-upload leaves its temporary
  // file): each `.tmp-*` file whose writer, by the PID in its name, is no longer alive here, or
  // that nobody wrote to for `stale` (another host's, on a shared folder). A live upload keeps
  // both. Returns how many were removed. Called when a scheduler or worker starts.
  std::size_t sweep_abandoned_uploads(std::chrono::seconds stale = std::chrono::hours(1)) const;
  // Where the blob named `sha256` lives (or would); InputError unless it is 64 lowercase hex digits.
  std::filesystem::path path_of(std::string_view sha256) const;

  // Streams one blob in. Destroying a writer that was not committed leaves nothing behind.
  class Writer {
   public:
    Writer(Writer&&) noexcept;
    Writer& operator=(Writer&&) = delete;
    Writer(const Writer&) = delete;
    ~Writer();

    // DiskFull (naming the store's folder) when the disk has no room for them.
    void append(std::string_view bytes);
    std::uint64_t bytes_written() const { return size_; }
    // Verifies the hash (and size) and publishes the blob. InputError on a mismatch; DiskFull
    // when the last bytes find no room.
    void commit();

   private:
    friend class AssetStore;
    Writer(const AssetStore& store, std::string sha256, std::optional<std::uint64_t> size);

    std::filesystem::path final_path_, temp_path_;
    std::string expected_sha256_;
    std::optional<std::uint64_t> expected_size_;
    int fd_ = -1;  // the temporary file, open until commit() or the destructor
    Sha256 hash_;
    std::uint64_t size_ = 0;
    bool done_ = false;
  };

  Writer begin(std::string_view expected_sha256,
               std::optional<std::uint64_t> expected_size = std::nullopt) const;

  // Whole-blob conveniences. put() verifies against `expected_sha256`; add() names the bytes by
  // their hash and returns it.
  void put(std::string_view expected_sha256, std::string_view bytes) const;
  std::string add(std::string_view bytes) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace farm
