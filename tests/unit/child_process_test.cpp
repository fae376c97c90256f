// ChildProcess's exit: the code, and the CPU time its threads used, which `farm bench render`
// shows as the cores a command kept busy (with the kernel's part and the peak memory beside
// them); nothing before the child has ended.
#include "server/common/child_process.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>

namespace farm {
namespace {

using namespace std::chrono_literals;

TEST(ChildProcess, ItsExitCodeAndCpuTimeComeOnceItHasEnded) {
  // A shell loop: a few tens of milliseconds of CPU, then exit code 3.
  ChildProcess busy({"/bin/sh", "-c", "i=0; while [ $i -lt 100000 ]; do i=$((i+1)); done; exit 3"});
  EXPECT_FALSE(busy.cpu_seconds().has_value());
  ASSERT_EQ(busy.wait_exit(60s), 3);
  ASSERT_TRUE(busy.cpu_seconds().has_value());
  EXPECT_GT(*busy.cpu_seconds(), 0.001);

  // A loop of the shell's own: its time is user time, and it holds little memory.
  ASSERT_TRUE(busy.kernel_seconds().has_value() && busy.peak_memory_bytes().has_value());
  EXPECT_LE(*busy.kernel_seconds(), *busy.cpu_seconds());
  EXPECT_LT(*busy.peak_memory_bytes(), std::uint64_t{32} << 20);

  // dd's 64 MiB buffer, filled from /dev/zero by the kernel four times: resident at its peak,
  // and the filling (and the buffer's first-touch page faults) counted as the kernel's time.
  ChildProcess copier({"/bin/dd", "if=/dev/zero", "of=/dev/null", "bs=64M", "count=4", "status=none"});
  ASSERT_EQ(copier.wait_exit(60s), 0);
  ASSERT_TRUE(copier.kernel_seconds().has_value() && copier.peak_memory_bytes().has_value());
  EXPECT_GE(*copier.peak_memory_bytes(), std::uint64_t{64} << 20);
  EXPECT_GT(*copier.kernel_seconds(), 0.0);
  EXPECT_GT(*copier.kernel_seconds(), 0.5 * *copier.cpu_seconds());

  // A child still running when the wait gives up has no CPU time yet.
  ChildProcess sleeper({"/bin/sleep", "30"});
  EXPECT_FALSE(sleeper.wait_exit(1ms).has_value());
  EXPECT_FALSE(sleeper.cpu_seconds().has_value());
  EXPECT_FALSE(sleeper.kernel_seconds().has_value());
  EXPECT_FALSE(sleeper.peak_memory_bytes().has_value());
  sleeper.send_signal(9);
  EXPECT_EQ(sleeper.wait_exit(60s), 128 + 9);
}

}  // namespace
}  // namespace farm
