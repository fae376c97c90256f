#include "tests/support/tmpfs_mount.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "server/common/disk_full.h"

namespace farm::test {

namespace fs = std::filesystem;

TmpfsMount::TmpfsMount(fs::path folder, std::uint64_t bytes) : folder_(std::move(folder)) {
  if (::geteuid() != 0) {
    problem_ = "mounting a tmpfs needs root (this test runs as uid " + std::to_string(::geteuid()) + ")";
    return;
  }
  fs::create_directories(folder_);
  const std::string options = fmt::format("size={}", bytes);
  if (::mount("tmpfs", folder_.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) != 0) {
    problem_ = fmt::format("mount -t tmpfs -o {} {}: {}", options, folder_.string(), std::strerror(errno));
    return;
  }
  mounted_ = true;
}

TmpfsMount::~TmpfsMount() {
  if (!mounted_) return;
  // A child that still holds a file there (a scheduler being killed) keeps it busy: detached then,
  // it goes once the last user does.
  if (::umount2(folder_.c_str(), 0) != 0) ::umount2(folder_.c_str(), MNT_DETACH);
}

std::uint64_t TmpfsMount::fill(const fs::path& file, std::uint64_t leave) const {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(fmt::format("cannot open {}: {}", file.string(), std::strerror(errno)));
  const std::string zeros(64 * 1024, '\0');
  // Written, not allocated sparse: a tmpfs counts the pages a file holds.
  for (std::uint64_t free = free_bytes(folder_).value_or(0); free > leave; free = free_bytes(folder_).value_or(0)) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(zeros.size(), free - leave));
    if (::write(fd, zeros.data(), n) < 0) {
      const int error = errno;
      if (error == EINTR) continue;
      if (error == ENOSPC) break;
      ::close(fd);
      throw std::runtime_error(fmt::format("cannot fill {}: {}", file.string(), std::strerror(error)));
    }
  }
  ::close(fd);
  return fs::file_size(file);
}

}  // namespace farm::test
