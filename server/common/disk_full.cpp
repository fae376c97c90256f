#include "server/common/disk_full.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view kPrefix = "disk full in ";

std::string message(const fs::path& folder, const std::string& refused) {
  const std::optional<std::uint64_t> free = free_bytes(folder);
  return fmt::format("{}{}: {} ({})", kPrefix, folder.string(), refused,
                     free ? describe_bytes(*free) + " free" : "free space unknown");
}

}  // namespace

DiskFull::DiskFull(fs::path folder, const std::string& refused, std::uint64_t needed)
    : std::runtime_error(message(folder, refused)), folder_(std::move(folder)), needed_(needed) {}

bool is_disk_full_errno(int error) { return error == ENOSPC || error == EDQUOT; }

void throw_write_error(int error, const fs::path& file, std::uint64_t needed) {
  const std::string refused = fmt::format("cannot write {}", file.string());
  if (is_disk_full_errno(error)) {
    throw DiskFull(file.parent_path(), fmt::format("{}: {}", refused, std::generic_category().message(error)), needed);
  }
  throw std::system_error(error, std::generic_category(), refused);
}

void write_all(int fd, std::string_view bytes, const fs::path& file) {
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw_write_error(errno, file, bytes.size());
    }
    written += static_cast<std::size_t>(n);
  }
}

void write_file(const fs::path& file, std::string_view bytes) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw_write_error(errno, file, bytes.size());
  try {
    write_all(fd, bytes, file);
  } catch (...) {
    ::close(fd);
    throw;
  }
  // A file system may only report the lack of space when the file is closed (NFS, quotas).
  if (::close(fd) != 0) throw_write_error(errno, file, bytes.size());
}

void rethrow_as_disk_full(const fs::path& folder) {
  try {
    throw;
  } catch (const std::system_error& e) {
    if (e.code().category() != std::generic_category() && e.code().category() != std::system_category()) throw;
    if (!is_disk_full_errno(e.code().value())) throw;
    throw DiskFull(folder, e.what());
  }
}

std::optional<std::uint64_t> free_bytes(const fs::path& folder) {
  struct statvfs s {};
  if (::statvfs(folder.c_str(), &s) != 0) return std::nullopt;
  return static_cast<std::uint64_t>(s.f_bavail) * s.f_frsize;
}

std::string describe_bytes(std::uint64_t bytes) {
  if (bytes < 1024) return fmt::format("{} bytes", bytes);
  constexpr const char* kUnits[] = {"KiB", "MiB", "GiB", "TiB"};
  double value = static_cast<double>(bytes) / 1024.0;
  std::size_t unit = 0;
  while (value >= 1024.0 && unit + 1 < std::size(kUnits)) {
    value /= 1024.0;
    ++unit;
  }
  return fmt::format("{:.1f} {}", value, kUnits[unit]);
}

bool is_disk_full(const grpc::Status& status) {
  return status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED &&
         std::string_view(status.error_message()).starts_with(kPrefix);
}

}  // namespace farm
