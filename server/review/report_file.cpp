#include "server/review/report_file.h"

#include <fmt/format.h>

#include <cstdio>
#include <stdexcept>

#include "renderer/image/output_file.h"

namespace farm {

namespace fs = std::filesystem;

void write_report_text(const fs::path& file, std::string_view text) {
  write_c_file_atomically(file, [&](std::FILE* out) {
    if (std::fwrite(text.data(), 1, text.size(), out) != text.size()) {
      throw std::runtime_error(fmt::format("{}: cannot write", file.string()));
    }
  });
}

void copy_report_file(const fs::path& from, const fs::path& to) {
  write_file_atomically(to, [&](const fs::path& temp) { fs::copy_file(from, temp, fs::copy_options::overwrite_existing); });
}

}  // namespace farm
