#include "server/bench/bench_support.h"

#include <gtest/gtest.h>

#include <string>

namespace farm::bench {
namespace {

// What every bench's first line names the CPU by: the first processor's "model name" of
// /proc/cpuinfo, as Linux writes it (a tab before the colon), cleaned of what a terminal should
// not be sent and bounded.
TEST(BenchSupport, TheCpuModelIsTheFirstModelNameLineCleanedAndBounded) {
  const std::string two_processors =
      "processor\t: 0\nvendor_id\t: AuthenticAMD\nmodel\t\t: 1\nmodel name\t: AMD EPYC 7B13  \n"
      "flags\t\t: fpu avx2\n\nprocessor\t: 1\nmodel name\t: Something Else\n";
  EXPECT_EQ(cpu_model_name(two_processors), "AMD EPYC 7B13");  // not "model", not the second
  EXPECT_EQ(cpu_model_name("model name\t: Intel(R) Xeon(R) CPU @ 2.20GHz"), "Intel(R) Xeon(R) CPU @ 2.20GHz");
  EXPECT_EQ(cpu_model_name("processor\t: 0\nBogoMIPS\t: 100.00\n"), "");  // an arm64 kernel's: none
  EXPECT_EQ(cpu_model_name(""), "");
  EXPECT_EQ(cpu_model_name("model name\t: A\x1b[31mB\tC\x7f\n"), "A[31mBC");
  EXPECT_EQ(cpu_model_name("model name: " + std::string(500, 'x') + "\n"), std::string(80, 'x'));
}

}  // namespace
}  // namespace farm::bench
