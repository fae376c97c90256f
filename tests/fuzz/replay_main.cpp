// The replay runner of the ordinary (gcc) builds: runs every file under the folders (or the files)
// given once through the target's LLVMFuzzerTestOneInput, as libFuzzer would run a crash input.
// An input that crashes fails the test by itself; one that runs longer than kSecondsPerInput or
// leaves the process over kMaxResidentMiB fails it here, as libFuzzer's -timeout and
// -rss_limit_mb would. Without libFuzzer this is how CI proves every committed regression input
// stays fixed.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_support.h"

namespace {

constexpr unsigned kSecondsPerInput = 5;
constexpr long kMaxResidentMiB = 2048;

const char* g_current = "";

void on_alarm(int) {
  // Only async-signal-safe calls here.
  const char prefix[] = "fuzz replay: input ran over its time limit: ";
  (void)!write(2, prefix, sizeof prefix - 1);
  (void)!write(2, g_current, std::strlen(g_current));
  (void)!write(2, "\n", 1);
  _exit(1);
}

std::vector<std::filesystem::path> inputs_under(const std::filesystem::path& root) {
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_regular_file(root)) return {root};
  if (!std::filesystem::is_directory(root)) return files;  // a target with no regressions yet
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

long resident_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024;  // kilobytes on Linux
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGALRM, on_alarm);
  std::size_t runs = 0;
  for (int i = 1; i < argc; ++i) {
    for (const std::filesystem::path& file : inputs_under(argv[i])) {
      std::ifstream in(file, std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const std::string name = file.string();
      g_current = name.c_str();
      alarm(kSecondsPerInput);
      const auto start = std::chrono::steady_clock::now();
      LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
      alarm(0);
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      std::printf("ran %s (%zu bytes) in %.1f ms\n", name.c_str(), bytes.size(), ms);
      if (resident_mib() > kMaxResidentMiB) {
        std::fprintf(stderr, "fuzz replay: %s left the process at %ld MiB (limit %ld)\n",
                     name.c_str(), resident_mib(), kMaxResidentMiB);
        return 1;
      }
      ++runs;
    }
  }
  if (runs == 0) {
    std::fprintf(stderr, "fuzz replay: no inputs under the folders given\n");
    return 1;
  }
  std::printf("fuzz replay: %zu inputs, none crashed\n", runs);
  return 0;
}
