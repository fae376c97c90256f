// ChildProcess's exit: the code, and the CPU time its threads used, which `farm bench render`
// shows as the cores a command kept busy; nothing before the child has ended.
#include "server/common/child_process.h"

#include <gtest/gtest.h>

#include <chrono>

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

  // A child still running when the wait gives up has no CPU time yet.
  ChildProcess sleeper({"/bin/sleep", "30"});
  EXPECT_FALSE(sleeper.wait_exit(1ms).has_value());
  EXPECT_FALSE(sleeper.cpu_seconds().has_value());
  sleeper.send_signal(9);
  EXPECT_EQ(sleeper.wait_exit(60s), 128 + 9);
}

}  // namespace
}  // namespace farm
