#include "renderer/util/confined_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <system_error>

#include "renderer/util/path_confinement.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMaxShown = 1024;  // a path, not a flood

std::atomic<std::uint64_t> g_confine_file_calls{0};

// A reference inside a message: shortened, so a hostile model cannot flood a log.
std::string shown(const std::string& s) {
  return s.size() <= kMaxShown ? s : s.substr(0, kMaxShown) + "...";
}

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link to no file";
  return "not a plain file";
}

}  // namespace

std::uint64_t confine_file_calls() { return g_confine_file_calls.load(std::memory_order_relaxed); }

ConfinedFile confine_file(const fs::path& root, const fs::path& referrer, const std::string& reference,
                          ReferenceForm form) {
  g_confine_file_calls.fetch_add(1, std::memory_order_relaxed);
  ConfinedFile out;
  const auto refuse = [&](Confinement verdict, const std::string& why) {
    out.verdict = verdict;
    out.reason = fmt::format("'{}' {}", shown(reference), why);
    out.message = fmt::format("{}: {}", referrer.string(), out.reason);
    return out;
  };
  if (reference.empty()) return out;  // names nothing: missing
  if (reference.find('\0') != std::string::npos) {
    return refuse(Confinement::inaccessible, "contains a NUL character");
  }
  const fs::path written(reference);
  if (written.has_root_path()) {
    if (form == ReferenceForm::relative) {
      return refuse(Confinement::absolute,
                    "is an absolute path (a model names its files relative to its own folder)");
    }
    out.named = written.lexically_normal();
  } else {
    out.named = (referrer.parent_path() / written).lexically_normal();
  }
  // A model's reference must stay in the root as written, since a farm lays the files out by the
  // names models use: `..` past the root is refused before anything is looked up. A job's path is
  // judged by where it resolves to alone (a submission renames it relative to the root), as its
  // folders may be named through links (../../shared -> /mnt/shared).
  const std::string outside = fmt::format("lies outside the asset root ({})", root.string());
  const bool named_inside = lies_within(root, out.named);
  if (!named_inside && form == ReferenceForm::relative) return refuse(Confinement::outside, outside);

  // Every symbolic link along the existing part resolved, so the test below sees where it leads.
  std::error_code ec;
  out.resolved = fs::weakly_canonical(out.named, ec);
  if (ec) return refuse(Confinement::inaccessible, fmt::format("cannot be resolved: {}", ec.message()));
  if (!lies_within(root, out.resolved)) {
    return refuse(Confinement::outside,
                  named_inside ? outside + ": a symbolic link on the way leads out" : outside);
  }

  // lstat, not stat: `resolved` holds no link but the last component of a dangling one, which must
  // not be followed later. Nothing is opened here, so a FIFO cannot make this wait.
  struct stat st {};
  if (::lstat(out.resolved.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT || err == ENOTDIR) {
      out.verdict = Confinement::missing;
      out.reason = fmt::format("'{}': no such file", shown(reference));
      out.message = fmt::format("{}: {}", referrer.string(), out.reason);
      return out;
    }
    return refuse(Confinement::inaccessible, fmt::format("cannot be looked at: {}", std::strerror(err)));
  }
  if (!S_ISREG(st.st_mode)) {
    return refuse(Confinement::not_regular, fmt::format("is {}, not a regular file", kind_of(st.st_mode)));
  }
  out.verdict = Confinement::allowed;
  out.size = static_cast<std::uintmax_t>(st.st_size);
  out.device = st.st_dev;
  out.inode = st.st_ino;
  return out;
}

int open_confined(const ConfinedFile& file, std::string* why) {
  const auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return -1;
  };
  if (!file.allowed()) return fail(file.message.empty() ? "no such file" : file.message);
  // O_NONBLOCK: should a FIFO have taken the file's place since it was looked at, opening it
  // returns at once instead of waiting for a writer. O_NOFOLLOW: nor is a link followed.
  const int fd = ::open(file.resolved.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NOFOLLOW | O_NONBLOCK);
  if (fd < 0) return fail(fmt::format("{}: cannot open: {}", file.resolved.string(), std::strerror(errno)));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_dev != file.device || st.st_ino != file.inode) {
    ::close(fd);
    return fail(fmt::format("{}: was replaced after it was checked; not read", file.resolved.string()));
  }
  // A regular file ignores O_NONBLOCK; cleared all the same, so readers get a plain descriptor.
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags != -1) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  return fd;
}

namespace {

template <typename Bytes>
bool read_all(const ConfinedFile& file, Bytes& bytes, std::string* why) {
  const int fd = open_confined(file, why);
  if (fd < 0) return false;
  bytes.clear();
  bytes.resize(static_cast<std::size_t>(file.size));
  std::size_t got = 0;
  for (;;) {
    if (got == bytes.size()) bytes.resize(got + 4096 + got / 2);  // it grew since it was looked at
    const ssize_t n = ::read(fd, bytes.data() + got, bytes.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      if (why) *why = fmt::format("{}: cannot read: {}", file.resolved.string(), std::strerror(err));
      return false;
    }
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  bytes.resize(got);
  return true;
}

}  // namespace

bool read_confined(const ConfinedFile& file, std::string& bytes, std::string* why) {
  return read_all(file, bytes, why);
}

bool read_confined(const ConfinedFile& file, std::vector<unsigned char>& bytes, std::string* why) {
  return read_all(file, bytes, why);
}

}  // namespace farm
