#pragma once
// SHA-256 (OpenSSL's EVP interface) as lowercase hex: the names of content-addressed assets and
// scene hashes (proto/farm.proto).
#include <cstddef>
#include <filesystem>
#include <istream>
#include <memory>
#include <string>
#include <string_view>

namespace farm {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  Sha256(Sha256&&) noexcept;
  Sha256& operator=(Sha256&&) noexcept;

  void update(const void* data, std::size_t size);
  void update(std::string_view bytes) { update(bytes.data(), bytes.size()); }
  // The digest of everything given so far, as 64 lowercase hex digits; the object is then spent.
  std::string finish_hex();

 private:
  struct Context;
  std::unique_ptr<Context> ctx_;
};

std::string sha256_hex(std::string_view bytes);
// Streams the file; throws std::runtime_error when it cannot be read.
std::string sha256_file_hex(const std::filesystem::path& file);
// What is left of `in`, read to its end; `name` says what it is in the error thrown when reading
// fails.
std::string sha256_stream_hex(std::istream& in, std::string_view name);
// 64 lowercase hex digits: the only form accepted as an asset name (it becomes a file name).
bool is_sha256_hex(std::string_view s);

}  // namespace farm
