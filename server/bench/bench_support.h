#pragma once
// Small helpers every `farm bench` command shares: medians, elapsed time, this program's path,
// a scratch folder.
#include <chrono>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace farm::bench {

// The median (the mean of the middle two for an even count); 0 for none.
double median(std::vector<double> values);

double ms_since(std::chrono::steady_clock::time_point start);
double seconds_since(std::chrono::steady_clock::time_point start);

// What a bench's figures were measured on, for its first line: the build type, the CPU's model
// name (the first in /proc/cpuinfo; "unknown CPU" where there is none), its hardware threads
// and the ray traversal build it runs (traversal_isa.h), e.g. "Release build, AMD EPYC, 2
// hardware threads, avx2 ray traversal". Figures from two machines do not compare, and the
// anchors (Embree, Mitsuba's JIT) move with the CPU by other amounts than ours.
std::string machine_summary();

// The model name in a /proc/cpuinfo text (its first "model name" line, printable ASCII, at most
// 80 characters); empty when it has none.
std::string cpu_model_name(std::string_view cpuinfo);

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
