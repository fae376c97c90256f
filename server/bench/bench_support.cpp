#include "server/bench/bench_support.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "renderer/geometry/traversal_isa.h"

namespace farm::bench {

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string cpu_model_name(std::string_view cpuinfo) {
  constexpr std::string_view kKey = "model name";
  constexpr std::size_t kMaxLength = 80;
  for (std::size_t start = 0; start < cpuinfo.size();) {
    const std::size_t end = std::min(cpuinfo.find('\n', start), cpuinfo.size());
    const std::string_view line = cpuinfo.substr(start, end - start);
    start = end + 1;
    if (line.substr(0, kKey.size()) != kKey) continue;
    const std::size_t colon = line.find(':');
    if (colon == std::string_view::npos) continue;
    std::string name;
    for (char c : line.substr(colon + 1)) {
      if (name.size() == kMaxLength) break;
      if (c >= ' ' && c <= '~' && !(name.empty() && c == ' ')) name += c;
    }
    while (!name.empty() && name.back() == ' ') name.pop_back();
    return name;
  }
  return {};
}

std::string machine_summary() {
  // /proc files report a size of 0: read up to a bound rather than by their size.
  std::string cpuinfo(64 * 1024, '\0');
  std::ifstream file("/proc/cpuinfo", std::ios::binary);
  file.read(cpuinfo.data(), static_cast<std::streamsize>(cpuinfo.size()));
  cpuinfo.resize(static_cast<std::size_t>(file.gcount()));
  const std::string model = cpu_model_name(cpuinfo);
  return fmt::format("{} build, {}, {} hardware threads, {} ray traversal", FARM_BUILD_TYPE,
                     model.empty() ? "unknown CPU" : model, std::thread::hardware_concurrency(),
                     to_string(best_traversal_isa()));
}

std::string self_binary() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the farm binary (/proc/self/exe)");
  return self.string();
}

ScratchDir::ScratchDir(const std::string& what)
    : path_(std::filesystem::temp_directory_path() / fmt::format("farm-{}-{}", what, ::getpid())) {
  std::filesystem::create_directories(path_);
}

ScratchDir::~ScratchDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace farm::bench
