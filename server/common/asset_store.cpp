#include "server/common/asset_store.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <signal.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <system_error>

#include "renderer/util/input_error.h"
#include "server/common/disk_full.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

// Unique within the folder across threads and processes sharing it.
fs::path temp_name(const fs::path& dir, std::string_view sha256) {
  static std::atomic<std::uint64_t> counter{0};
  return dir / fmt::format(".tmp-{}-{}-{}", sha256.substr(0, 16), ::getpid(), counter++);
}

}  // namespace

AssetStore::AssetStore(fs::path dir) : dir_(std::move(dir)) { fs::create_directories(dir_); }

std::size_t AssetStore::sweep_abandoned_uploads(std::chrono::seconds stale) const {
  std::size_t removed = 0;
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(".tmp-", 0) != 0) continue;
    // .tmp-<hash prefix>-<pid>-<counter>
    bool writer_gone = false;
    const std::size_t last = name.rfind('-'), before = last == std::string::npos ? last : name.rfind('-', last - 1);
    if (before != std::string::npos) {
      const std::string pid_text = name.substr(before + 1, last - before - 1);
      char* stop = nullptr;
      const long pid = std::strtol(pid_text.c_str(), &stop, 10);
      writer_gone = !pid_text.empty() && *stop == '\0' && pid > 0 && pid != ::getpid() && ::kill(static_cast<pid_t>(pid), 0) != 0 &&
                    errno == ESRCH;
    }
    std::error_code time_ec;
    const auto written = fs::last_write_time(it->path(), time_ec);
    const bool idle = !time_ec && now - written > stale;
    if (!writer_gone && !idle) continue;
    std::error_code remove_ec;
    if (fs::remove(it->path(), remove_ec)) ++removed;
  }
  return removed;
}

bool AssetStore::has(std::string_view sha256) const {
  if (!is_sha256_hex(sha256)) return false;
  std::error_code ec;
  return fs::is_regular_file(dir_ / std::string(sha256), ec);
}

bool AssetStore::intact(std::string_view sha256) const {
  if (!has(sha256)) return false;
  std::ifstream in(path_of(sha256), std::ios::binary);
  if (!in) return false;
  Sha256 hash;
  std::string buffer(1 << 16, '\0');
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    hash.update(buffer.data(), static_cast<std::size_t>(in.gcount()));
  }
  return !in.bad() && hash.finish_hex() == sha256;
}

void AssetStore::remove(std::string_view sha256) const {
  std::error_code ignored;
  fs::remove(path_of(sha256), ignored);
}

fs::path AssetStore::path_of(std::string_view sha256) const {
  if (!is_sha256_hex(sha256)) {
    throw InputError(fmt::format("'{}' is not a SHA-256 (64 lowercase hex digits)",
                                 sha256.substr(0, 80)));
  }
  return dir_ / std::string(sha256);
}

AssetStore::Writer AssetStore::begin(std::string_view expected_sha256,
                                     std::optional<std::uint64_t> expected_size) const {
  return Writer(*this, std::string(expected_sha256), expected_size);
}

AssetStore::Writer::Writer(const AssetStore& store, std::string sha256,
                           std::optional<std::uint64_t> size)
    : final_path_(store.path_of(sha256)),
      temp_path_(temp_name(store.dir(), sha256)),
      expected_sha256_(std::move(sha256)),
      expected_size_(size),
      fd_(::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644)) {
  if (fd_ < 0) throw_write_error(errno, temp_path_, size.value_or(0));
}

AssetStore::Writer::Writer(Writer&& o) noexcept
    : final_path_(std::move(o.final_path_)),
      temp_path_(std::move(o.temp_path_)),
      expected_sha256_(std::move(o.expected_sha256_)),
      expected_size_(o.expected_size_),
      fd_(o.fd_),
      hash_(std::move(o.hash_)),
      size_(o.size_),
      done_(o.done_) {
  o.fd_ = -1;
  o.done_ = true;  // the moved-from writer owns no temporary file any more
}

AssetStore::Writer::~Writer() {
  if (fd_ >= 0) ::close(fd_);
  if (done_) return;
  std::error_code ec;
  fs::remove(temp_path_, ec);
}

void AssetStore::Writer::append(std::string_view bytes) {
  if (expected_size_ && size_ + bytes.size() > *expected_size_) {
    throw InputError(fmt::format("asset {}: more than the announced {} bytes", expected_sha256_,
                                 *expected_size_));
  }
  if (fd_ < 0) throw std::logic_error("AssetStore::Writer: append after commit");
  write_all(fd_, bytes, temp_path_);
  hash_.update(bytes);
  size_ += bytes.size();
}

void AssetStore::Writer::commit() {
  if (fd_ < 0) throw std::logic_error("AssetStore::Writer: committed twice");
  const int closed = ::close(fd_);
  fd_ = -1;
  // A file system may only report the lack of space when the file is closed (NFS, quotas).
  if (closed != 0) throw_write_error(errno, temp_path_, size_);
  if (expected_size_ && size_ != *expected_size_) {
    throw InputError(fmt::format("asset {}: got {} bytes, expected {}", expected_sha256_, size_,
                                 *expected_size_));
  }
  const std::string actual = hash_.finish_hex();
  if (actual != expected_sha256_) {
    throw InputError(fmt::format("asset {}: content hashes to {}", expected_sha256_, actual));
  }
  // rename() replaces atomically; a concurrent writer of the same blob wrote the same bytes.
  fs::rename(temp_path_, final_path_);
  done_ = true;
}

void AssetStore::put(std::string_view expected_sha256, std::string_view bytes) const {
  Writer w = begin(expected_sha256, bytes.size());
  w.append(bytes);
  w.commit();
}

std::string AssetStore::add(std::string_view bytes) const {
  std::string sha = sha256_hex(bytes);
  put(sha, bytes);
  return sha;
}

}  // namespace farm
