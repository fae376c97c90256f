#include "renderer/loaders/confined_io_system.h"

#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace farm {
namespace {

// An open, checked file descriptor as Assimp reads it (fread-like counts of whole elements).
class FdStream final : public Assimp::IOStream {
 public:
  FdStream(int fd, std::size_t size) : fd_(fd), size_(size) {}
  ~FdStream() override { ::close(fd_); }
  FdStream(const FdStream&) = delete;
  FdStream& operator=(const FdStream&) = delete;

  std::size_t Read(void* buffer, std::size_t size, std::size_t count) override {
    if (size == 0 || count == 0) return 0;
    auto* out = static_cast<char*>(buffer);
    const std::size_t wanted = size * count;
    std::size_t got = 0;
    while (got < wanted) {
      const ssize_t n = ::read(fd_, out + got, wanted - got);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      got += static_cast<std::size_t>(n);
    }
    return got / size;
  }
  std::size_t Write(const void*, std::size_t, std::size_t) override { return 0; }
  aiReturn Seek(std::size_t offset, aiOrigin origin) override {
    const int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    return ::lseek(fd_, static_cast<off_t>(offset), whence) < 0 ? aiReturn_FAILURE : aiReturn_SUCCESS;
  }
  std::size_t Tell() const override {
    const off_t at = ::lseek(fd_, 0, SEEK_CUR);
    return at < 0 ? 0 : static_cast<std::size_t>(at);
  }
  std::size_t FileSize() const override { return size_; }
  void Flush() override {}

 private:
  int fd_;
  std::size_t size_;
};

}  // namespace

ConfinedFile ConfinedIOSystem::confine(const char* file) const {
  ConfinedFile c = confine_loader_path(model_, file ? file : "");
  if (c.refused() && refusal_.empty()) refusal_ = c.reason;
  return c;
}

bool ConfinedIOSystem::Exists(const char* file) const {
  return confine(file).verdict != Confinement::missing;
}

Assimp::IOStream* ConfinedIOSystem::Open(const char* file, const char* mode) {
  if (mode && (std::strchr(mode, 'w') || std::strchr(mode, 'a') || std::strchr(mode, '+'))) return nullptr;
  const ConfinedFile c = confine(file);
  if (!c.allowed()) return nullptr;
  std::string why;
  const int fd = open_confined(c, &why);
  if (fd < 0) {
    if (refusal_.empty()) refusal_ = why;
    return nullptr;
  }
  return new FdStream(fd, static_cast<std::size_t>(c.size));
}

void ConfinedIOSystem::Close(Assimp::IOStream* stream) { delete stream; }

}  // namespace farm
