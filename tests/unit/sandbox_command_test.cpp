// The bwrap command line of a sandboxed run (server/grade/sandbox_command.h): the host's root is
// never mounted, the run's folders are (parents first, read-only unless writable), the
// environment is built from nothing, and setpriv drops to the run's user before the program.
#include "server/grade/sandbox_command.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace farm {
namespace {

using Args = std::vector<std::string>;

// Where `needle` (a run of arguments) starts in `args`, or args.size().
std::size_t find(const Args& args, const Args& needle) {
  return static_cast<std::size_t>(std::search(args.begin(), args.end(), needle.begin(), needle.end()) - args.begin());
}

SandboxRun example_run() {
  SandboxRun run;
  run.argv = {"./prog", "--flag"};
  run.workdir = "/work";
  run.mounts = {{"/srv/in/data", "/work/data", false}, {"/srv/student", "/work", true}};
  run.environment = {{"SEED", "7"}};
  run.limits.work_folder_mib = 100;
  return run;
}

TEST(SandboxCommand, MountsTheSystemReadOnlyAndNeverTheHostsRoot) {
  const Args args = sandbox_command(example_run(), {"/usr/bin/bwrap", "/usr/bin/setpriv"}, 2000000042, 3);
  EXPECT_EQ(args.front(), "/usr/bin/bwrap");
  EXPECT_LT(find(args, {"--pidns", "3"}), args.size());
  EXPECT_LT(find(args, {"--ro-bind", "/usr", "/usr"}), args.size());
  EXPECT_LT(find(args, {"--ro-bind", "/etc", "/etc"}), args.size());
  EXPECT_EQ(find(args, {"--ro-bind", "/", "/"}), args.size());
  EXPECT_EQ(find(args, {"--bind", "/", "/"}), args.size());
  for (const char* flag : {"--unshare-net", "--unshare-ipc", "--die-with-parent", "--new-session", "--clearenv"}) {
    EXPECT_LT(find(args, {flag}), args.size()) << flag;
  }
  EXPECT_EQ(find(args, {"--unshare-user"}), args.size());  // it would map the program to root outside
  EXPECT_LT(find(args, {"--perms", "1777", "--size", "104857600", "--tmpfs", "/tmp"}), args.size());
}

TEST(SandboxCommand, MountsTheRunsFoldersParentsFirst) {
  const Args args = sandbox_command(example_run(), {"/usr/bin/bwrap", "/usr/bin/setpriv"}, 2000000042, 3);
  const std::size_t work = find(args, {"--bind", "/srv/student", "/work"});
  const std::size_t data = find(args, {"--ro-bind", "/srv/in/data", "/work/data"});
  ASSERT_LT(work, args.size());
  ASSERT_LT(data, args.size());
  EXPECT_LT(work, data);
  EXPECT_EQ(find(args, {"--dir", "/work"}), args.size());  // mounted, so not made
  EXPECT_LT(find(args, {"--chdir", "/work"}), args.size());
}

TEST(SandboxCommand, BuildsTheEnvironmentAndDropsToTheRunsUser) {
  const Args args = sandbox_command(example_run(), {"/usr/bin/bwrap", "/usr/bin/setpriv"}, 2000000042, 3);
  EXPECT_LT(find(args, {"--setenv", "PATH", "/usr/bin:/bin"}), args.size());
  EXPECT_LT(find(args, {"--setenv", "HOME", "/work"}), args.size());
  EXPECT_LT(find(args, {"--setenv", "LANG", "C.UTF-8"}), args.size());
  EXPECT_LT(find(args, {"--setenv", "SEED", "7"}), args.size());
  const Args tail = {"--",
                     "/usr/bin/setpriv",
                     "--reuid=2000000042",
                     "--regid=2000000042",
                     "--clear-groups",
                     "--inh-caps=-all",
                     "--bounding-set=-all",
                     "--no-new-privs",
                     "--",
                     "./prog",
                     "--flag"};
  ASSERT_GE(args.size(), tail.size());
  EXPECT_EQ(Args(args.end() - static_cast<std::ptrdiff_t>(tail.size()), args.end()), tail);
}

TEST(SandboxCommand, MakesAWorkingFolderNoMountHolds) {
  SandboxRun run = example_run();
  run.workdir = "/scratch";
  const Args args = sandbox_command(run, {"/usr/bin/bwrap", "/usr/bin/setpriv"}, 2000000042, 3);
  EXPECT_LT(find(args, {"--dir", "/scratch"}), find(args, {"--chdir", "/scratch"}));
}

TEST(SandboxCommand, RefusesARunThatCannotWork) {
  SandboxRun run = example_run();
  run.mounts.clear();
  EXPECT_EQ(check_sandbox_run(run), "");
  run.workdir = "work";
  EXPECT_NE(check_sandbox_run(run).find("not an absolute path"), std::string::npos);
  run.workdir = "/work";
  run.mounts = {{"/no/such/folder/anywhere", "/in", false}};
  EXPECT_NE(check_sandbox_run(run).find("does not exist"), std::string::npos);
  run.mounts = {{"/usr", "/", false}};
  EXPECT_NE(check_sandbox_run(run).find("not an absolute folder below /"), std::string::npos);
  run.mounts.clear();
  run.argv.clear();
  EXPECT_EQ(check_sandbox_run(run), "no program to run");
}

}  // namespace
}  // namespace farm
