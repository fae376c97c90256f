#include "renderer/util/atomic_file.h"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <system_error>
#include "renderer/util/c_file.h"

namespace farm {

void write_file_atomically(const std::filesystem::path& target,
                           const std::function<void(const std::filesystem::path&)>& write) {
  namespace fs = std::filesystem;
  static std::atomic<unsigned> counter{0};
  const fs::path folder = target.parent_path();
  if (!folder.empty()) fs::create_directories(folder);
  const fs::path temp = folder / fmt::format(".{}.tmp{}-{}{}", target.stem().string(), getpid(),
                                             counter++, target.extension().string());
  try {
    write(temp);
    fs::rename(temp, target);
  } catch (...) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw;
  }
}

void write_c_file_atomically(const std::filesystem::path& target, const std::function<void(std::FILE*)>& write) {
  write_file_atomically(target, [&](const std::filesystem::path& temp) {
    // The deleter closes it if `write` throws; otherwise it is closed below, where the result counts.
    CFile out(std::fopen(temp.c_str(), "wb"));
    // Errors keep their errno (std::system_error), so that a server tells a full disk (ENOSPC)
    // from a broken image.
    if (!out) {
      throw std::system_error(errno, std::generic_category(),
                              fmt::format("{}: cannot create {}", target.string(), temp.string()));
    }
    write(out.get());
    if (std::fclose(out.release()) != 0) {
      throw std::system_error(errno, std::generic_category(), fmt::format("{}: cannot write", target.string()));
    }
  });
}

void write_text_atomically(const std::filesystem::path& target, std::string_view bytes) {
  write_c_file_atomically(target, [&](std::FILE* out) {
    if (std::fwrite(bytes.data(), 1, bytes.size(), out) != bytes.size()) {
      throw std::system_error(errno, std::generic_category(), fmt::format("{}: cannot write", target.string()));
    }
  });
}

void copy_file_atomically(const std::filesystem::path& from, const std::filesystem::path& to) {
  write_file_atomically(to, [&](const std::filesystem::path& temp) {
    std::filesystem::copy_file(from, temp, std::filesystem::copy_options::overwrite_existing);
  });
}

}  // namespace farm
