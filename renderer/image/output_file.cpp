#include "renderer/image/output_file.h"

#include <unistd.h>

#include <fmt/format.h>

#include <atomic>

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

}  // namespace farm
