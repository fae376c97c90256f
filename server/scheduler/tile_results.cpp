#include "server/scheduler/tile_results.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace farm {

namespace fs = std::filesystem;

TileResults::TileResults(fs::path dir) : dir_(std::move(dir)) { fs::create_directories(dir_); }

fs::path TileResults::path_of(const std::string& job_id, std::uint32_t part) const {
  return dir_ / job_id / std::to_string(part);
}

void TileResults::write(const std::string& job_id, std::uint32_t part,
                        const v1::RenderTileResponse& tile) const {
  static std::atomic<std::uint64_t> counter{0};
  const fs::path final_path = path_of(job_id, part);
  fs::create_directories(final_path.parent_path());
  const fs::path temp = final_path.parent_path() /
                        fmt::format(".tmp-{}-{}-{}", part, ::getpid(), counter++);
  const std::string bytes = tile.SerializeAsString();
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::system_error(errno, std::generic_category(), "cannot write " + temp.string());
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int e = errno;
      ::close(fd);
      ::unlink(temp.c_str());
      throw std::system_error(e, std::generic_category(), "cannot write " + temp.string());
    }
    written += static_cast<std::size_t>(n);
  }
  ::close(fd);
  fs::rename(temp, final_path);
}

v1::RenderTileResponse TileResults::read(const std::string& job_id, std::uint32_t part) const {
  const fs::path file = path_of(job_id, part);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("result {} of job {}: {} is missing", part, job_id, file.string()));
  std::ostringstream s;
  s << in.rdbuf();
  v1::RenderTileResponse tile;
  if (!tile.ParseFromString(s.str())) {
    throw std::runtime_error(fmt::format("result {} of job {}: {} is corrupt", part, job_id, file.string()));
  }
  return tile;
}

void TileResults::remove_job(const std::string& job_id) const {
  std::error_code ignored;
  fs::remove_all(dir_ / job_id, ignored);
}

}  // namespace farm
