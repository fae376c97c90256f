#include "server/scheduler/jobs/tile_results.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "renderer/util/atomic_file.h"
#include "server/common/disk_full.h"
#include "server/common/remove_tree.h"
#include "server/common/sha256.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view kMagic = "FARMTIL1";
constexpr std::size_t kLengthBytes = 8;
constexpr std::size_t kHashChars = 64;
constexpr std::size_t kHeaderBytes = kMagic.size() + kLengthBytes + kHashChars;

std::string header_of(std::string_view payload) {
  std::string header(kMagic);
  std::uint64_t n = payload.size();
  for (std::size_t i = 0; i < kLengthBytes; ++i, n >>= 8) header.push_back(static_cast<char>(n & 0xff));
  header += sha256_hex(payload);
  return header;
}

}  // namespace

TileResults::TileResults(fs::path dir) : dir_(std::move(dir)) { fs::create_directories(dir_); }

fs::path TileResults::path_of(const std::string& job_id, std::uint32_t part) const {
  return dir_ / job_id / std::to_string(part);
}

void TileResults::write(const std::string& job_id, std::uint32_t part,
                        const v1::RenderTileResponse& tile) const {
  const fs::path final_path = path_of(job_id, part);
  const std::string payload = tile.SerializeAsString();
  const std::string bytes = header_of(payload) + payload;
  try {
    fs::create_directories(final_path.parent_path());
  } catch (const std::exception&) {
    rethrow_as_disk_full(dir_);
  }
  write_file_atomically(final_path, [&](const fs::path& temp) { write_file(temp, bytes); });
}

v1::RenderTileResponse TileResults::read(const std::string& job_id, std::uint32_t part) const {
  const fs::path file = path_of(job_id, part);
  const auto damaged = [&](std::string_view problem) {
    return DamagedTileResult(file, fmt::format("result {} of job {}: {} {}", part, job_id, file.string(), problem));
  };
  std::ifstream in(file, std::ios::binary);
  if (!in) throw damaged("is missing or unreadable");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw damaged("cannot be read");
  const std::string bytes = std::move(s).str();
  if (bytes.size() < kHeaderBytes || std::string_view(bytes).substr(0, kMagic.size()) != kMagic) {
    throw damaged(fmt::format("has no result header ({} bytes)", bytes.size()));
  }
  std::uint64_t length = 0;
  for (std::size_t i = kLengthBytes; i-- > 0;) {
    length = (length << 8) | static_cast<unsigned char>(bytes[kMagic.size() + i]);
  }
  const std::string_view payload = std::string_view(bytes).substr(kHeaderBytes);
  if (payload.size() != length) {
    throw damaged(fmt::format("is truncated or padded: {} bytes of result, the header says {}", payload.size(), length));
  }
  const std::string_view expected = std::string_view(bytes).substr(kMagic.size() + kLengthBytes, kHashChars);
  if (sha256_hex(payload) != expected) throw damaged("fails its checksum (SHA-256 of the result differs)");
  v1::RenderTileResponse tile;
  if (!tile.ParseFromArray(payload.data(), static_cast<int>(payload.size()))) throw damaged("does not parse");
  return tile;
}

void TileResults::remove(const std::string& job_id, std::uint32_t part) const {
  std::error_code ignored;
  fs::remove(path_of(job_id, part), ignored);
}

std::uintmax_t TileResults::remove_job(const std::string& job_id) const {
  try {
    return remove_tree(dir_ / job_id);
  } catch (const fs::filesystem_error&) {
    return 0;  // what is left is removed with the job (farm delete) or never read again
  }
}

}  // namespace farm
