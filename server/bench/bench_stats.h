#pragma once
// Small helpers every `farm bench` command shares: medians, elapsed time, this program's path.
#include <chrono>
#include <string>
#include <vector>

namespace farm::bench {

// The median (the mean of the middle two for an even count); 0 for none.
double median(std::vector<double> values);

double ms_since(std::chrono::steady_clock::time_point start);

// This very `farm` binary, for benchmarks that start it as a child process.
std::string self_binary();

}  // namespace farm::bench
