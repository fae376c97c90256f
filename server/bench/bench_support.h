#pragma once
// Small helpers every `farm bench` command shares: medians, elapsed time, this program's path,
// a scratch folder.
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace farm::bench {

// The median (the mean of the middle two for an even count); 0 for none.
double median(std::vector<double> values);

double ms_since(std::chrono::steady_clock::time_point start);
double seconds_since(std::chrono::steady_clock::time_point start);

// This very `farm` binary, for benchmarks that start it as a child process.
std::string self_binary();

// A fresh folder under the temp dir named after `what` and this process, removed with its
// contents when this goes out of scope.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& what);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace farm::bench
