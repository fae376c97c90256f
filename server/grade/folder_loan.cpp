#include "server/grade/folder_loan.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace farm {
namespace {

namespace fs = std::filesystem;

// Chowns `root` and everything under it; false (errno set) when `root` itself cannot be.
bool chown_all(const fs::path& root, uid_t uid, gid_t gid) {
  if (lchown(root.c_str(), uid, gid) != 0) return false;
  std::error_code ec;
  // The iterator does not follow directory symlinks; what vanishes meanwhile is skipped.
  for (fs::recursive_directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    lchown(it->path().c_str(), uid, gid);
  }
  return true;
}

}  // namespace

FolderLoan::FolderLoan(const std::vector<fs::path>& folders, uid_t uid, gid_t gid) {
  for (const fs::path& folder : folders) {
    std::error_code ec;
    const fs::path real = fs::canonical(folder, ec);  // what bwrap mounts when it is a symlink
    struct stat info {};
    if (ec || lstat(real.c_str(), &info) != 0 || !chown_all(real, uid, gid)) {
      if (ec) errno = ec.value();
      const std::string why = std::strerror(errno);
      give_back();  // what was lent so far
      throw std::runtime_error("cannot lend " + folder.string() + " to the sandbox's user: " + why);
    }
    owners_.push_back({real, info.st_uid, info.st_gid});
  }
}

FolderLoan::~FolderLoan() { give_back(); }

void FolderLoan::give_back() {
  // Last lent first: a folder inside another (or lent twice) saw the sandbox's user as its owner.
  for (auto owner = owners_.rbegin(); owner != owners_.rend(); ++owner) chown_all(owner->folder, owner->uid, owner->gid);
  owners_.clear();
}

}  // namespace farm
