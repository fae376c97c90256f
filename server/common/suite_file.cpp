#include "server/common/suite_file.h"

#include <fmt/format.h>

#include <cctype>
#include <cstdio>

#include "renderer/util/input_error.h"

namespace farm {

namespace fs = std::filesystem;

namespace {
constexpr std::size_t kMaxBytes = 4 << 20;  // such a file lists jobs; megabytes of it are a mistake
}  // namespace

std::string read_bounded_text(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) {
    throw InputError(fmt::format("{}: {}", file.string(), fs::exists(file, ec) ? "not a regular file" : "no such file"));
  }
  if (fs::file_size(file, ec) > kMaxBytes) {
    throw InputError(fmt::format("{}: larger than {} MiB", file.string(), kMaxBytes >> 20));
  }
  std::FILE* in = std::fopen(file.c_str(), "rb");
  if (in == nullptr) throw InputError(fmt::format("{}: cannot open for reading", file.string()));
  std::string text(kMaxBytes + 1, '\0');
  text.resize(std::fread(text.data(), 1, text.size(), in));
  std::fclose(in);
  return text;
}

bool is_safe_name(const std::string& name) {
  if (name.empty() || name.size() > 100 || name == "." || name == "..") return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') return false;
  return true;
}

fs::path resolve_from(const fs::path& folder, const std::string& text) { return fs::weakly_canonical(folder / fs::path(text)); }

fs::path read_folder(const std::optional<JsonValue>& value, const fs::path& folder) {
  if (!value) return folder;
  const fs::path path = resolve_from(folder, value->string());
  std::error_code ec;
  if (!fs::is_directory(path, ec)) value->fail(fmt::format("{} is not a folder", path.string()));
  return path;
}

fs::path read_job_path(const JsonValue& value, const fs::path& folder) {
  const fs::path job = resolve_from(folder, value.string());
  std::error_code ec;
  if (!fs::is_regular_file(job, ec)) value.fail(fmt::format("no job file at {}", job.string()));
  return job;
}

}  // namespace farm
