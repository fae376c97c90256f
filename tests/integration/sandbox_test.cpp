// The grading sandbox (server/grade/sandbox.h) against what a student's program might do: open
// the network, read what is not its own, fork without end, loop, eat memory, fill the disk,
// print without end; and a well-behaved program, which must simply work. Every hostile one is
// stopped or refused with the right SandboxEnd, fast, and leaves nothing running.
#include "server/grade/sandbox.h"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "server/grade/sandbox_watch.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class SandboxTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Not a skip: CI installs bubblewrap (deploy/install-deps.sh), so a missing one is a failure.
    ASSERT_TRUE(sandbox_available()) << "bubblewrap (bwrap) missing or unable to make namespaces here";
    fs::create_directories(work_);
    dir_.write("input/in.txt", "the input\n");
  }

  // A run in /work (writable: dir_/work) with /input (read-only: dir_/input) and small limits.
  SandboxRun run_of(std::vector<std::string> argv) const {
    SandboxRun run;
    run.argv = std::move(argv);
    run.workdir = "/work";
    run.mounts = {{work_, "/work", true}, {dir_ / "input", "/input", false}};
    run.limits.wall_seconds = 10.0;
    run.limits.cpu_seconds = 10.0;
    run.limits.memory_mib = 256;
    run.limits.processes = 32;
    run.limits.file_size_mib = 64;
    run.limits.work_folder_mib = 64;
    return run;
  }
  SandboxRun shell(const std::string& script) const { return run_of({"sh", "-c", script}); }

  // Compiles a C program into the work folder; returns its path inside the sandbox.
  std::string compile(const std::string& name, const std::string& source) const {
    const fs::path c = dir_.write(name + ".c", source);
    const test::CommandResult cc = test::run_command(
        "cc -O0 -o " + test::shell_quote((work_ / name).string()) + " " + test::shell_quote(c.string()));
    EXPECT_EQ(cc.exit_code, 0) << cc.output;
    return "/work/" + name;
  }

  // The processes of the sandbox user this thread's runs get: none may outlive a run.
  static int processes_left() { return count_processes_of(static_cast<uid_t>(2'000'000'000u + gettid())); }

  test::TempDir dir_;
  fs::path work_ = dir_ / "work";
};

TEST_F(SandboxTest, IsAvailableHere) { EXPECT_TRUE(sandbox_available()); }

TEST_F(SandboxTest, NetworkIsUnreachableEvenOnLoopback) {
  const int listener = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(listener, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  ASSERT_EQ(bind(listener, reinterpret_cast<sockaddr*>(&address), length), 0);
  ASSERT_EQ(listen(listener, 4), 0);
  ASSERT_EQ(getsockname(listener, reinterpret_cast<sockaddr*>(&address), &length), 0);
  const int port = ntohs(address.sin_port);

  const SandboxResult local = run_sandboxed(run_of(
      {"python3", "-c", "import socket\nsocket.create_connection(('127.0.0.1', " + std::to_string(port) +
                            "), timeout=3)\nprint('connected')"}));
  EXPECT_EQ(local.end, SandboxEnd::exited) << local.reason({}) << "\n" << local.output;
  EXPECT_NE(local.exit_code, 0);
  EXPECT_NE(local.output.find("ConnectionRefusedError"), std::string::npos) << local.output;
  EXPECT_EQ(local.output.find("connected\n"), std::string::npos) << local.output;
  pollfd pending{listener, POLLIN, 0};
  EXPECT_EQ(poll(&pending, 1, 0), 0) << "the listener outside saw a connection";
  close(listener);

  const SandboxResult outside = run_sandboxed(
      run_of({"python3", "-c", "import socket\nsocket.create_connection(('1.1.1.1', 80), timeout=3)\nprint('connected')"}));
  EXPECT_EQ(outside.end, SandboxEnd::exited) << outside.output;
  EXPECT_NE(outside.exit_code, 0);
  EXPECT_NE(outside.output.find("Network is unreachable"), std::string::npos) << outside.output;
}

TEST_F(SandboxTest, SeesNothingOfTheHostButTheSystemAndItsFolders) {
  const fs::path secret = dir_.write("secret.txt", "TOP-SECRET-4711\n");  // beside its folders, not in them
  const std::string script = "cat " + secret.string() + "; cat /root/.bashrc; ls /root " + dir_.path().string() +
                             "; ls /; cat /etc/shadow; cat /input/in.txt";
  const SandboxResult r = run_sandboxed(shell(script));
  EXPECT_EQ(r.end, SandboxEnd::exited) << r.output;
  EXPECT_EQ(r.output.find("TOP-SECRET"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(secret.string() + ": No such file or directory"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("/root/.bashrc: No such file or directory"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("/etc/shadow: Permission denied"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the input"), std::string::npos) << r.output;
  // The root holds the system, its folders and what bwrap makes; no work/, root/, home/, tmp of the host.
  EXPECT_EQ(r.output.find("\nhome\n"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\nroot\n"), std::string::npos) << r.output;
}

TEST_F(SandboxTest, ForkBombIsStoppedAtItsProcessLimit) {
  const std::string bomb = compile("bomb", "#include <unistd.h>\nint main(void) { for (;;) fork(); }\n");
  SandboxRun run = run_of({bomb});
  run.limits.wall_seconds = 5.0;
  const SandboxResult r = run_sandboxed(run);
  EXPECT_EQ(r.end, SandboxEnd::processes) << r.reason(run.limits) << "\n" << r.output;
  EXPECT_EQ(r.reason(run.limits), "started too many processes (limit 32): killed after a second at the limit");
  EXPECT_LT(r.wall_seconds, 4.0);
  EXPECT_EQ(processes_left(), 0);

  // The shell kind, background jobs started in a loop: bash retries a fork that fails at 32
  // ("fork: retry: Resource temporarily unavailable") and so sits at the limit; dash gives up.
  const SandboxResult bash = run_sandboxed(run_of({"bash", "-c", "while :; do sleep 30 & done"}));
  EXPECT_EQ(bash.end, SandboxEnd::processes) << bash.output;
  EXPECT_NE(bash.output.find("fork: retry"), std::string::npos) << bash.output;
  const SandboxResult dash = run_sandboxed(shell("while :; do sleep 30 & done"));
  EXPECT_EQ(dash.end, SandboxEnd::exited) << dash.output;
  EXPECT_EQ(dash.exit_code, 2);
  EXPECT_NE(dash.output.find("Cannot fork"), std::string::npos) << dash.output;
  EXPECT_EQ(processes_left(), 0);  // the sleeps it left went with it

  // The classic one returns at once, and the bomb it left in the background goes with it.
  const SandboxResult classic = run_sandboxed(run_of({"bash", "-c", ":(){ :|:& };:"}));
  EXPECT_EQ(classic.end, SandboxEnd::exited) << classic.output;
  EXPECT_LT(classic.wall_seconds, 2.0);
  EXPECT_EQ(processes_left(), 0);
}

TEST_F(SandboxTest, EndlessLoopRunsOutOfWallTimeOrCpuTime) {
  SandboxRun wall = shell("while :; do :; done");
  wall.limits.wall_seconds = 1.0;
  const SandboxResult by_wall = run_sandboxed(wall);
  EXPECT_EQ(by_wall.end, SandboxEnd::wall_time) << by_wall.output;
  EXPECT_EQ(by_wall.reason(wall.limits), "ran past its 1 s time limit");
  EXPECT_GE(by_wall.wall_seconds, 1.0);
  EXPECT_LT(by_wall.wall_seconds, 2.5);

  SandboxRun cpu = shell("while :; do :; done");
  cpu.limits.cpu_seconds = 1.0;
  const SandboxResult by_cpu = run_sandboxed(cpu);
  EXPECT_EQ(by_cpu.end, SandboxEnd::cpu_time) << by_cpu.output;
  EXPECT_EQ(by_cpu.signal, SIGXCPU);
  EXPECT_EQ(by_cpu.reason(cpu.limits), "used more than its 1 s of CPU time");
  EXPECT_GE(by_cpu.cpu_seconds, 0.9);
  EXPECT_LT(by_cpu.wall_seconds, 6.0);  // the CPU limit, not the wall one (10 s), ended it
  EXPECT_EQ(processes_left(), 0);
}

TEST_F(SandboxTest, AllocatingTenGibibytesRunsOutOfMemory) {
  // 10 GiB a MiB at a time, each touched: refused at 256 MiB, then NULL is written to.
  const std::string hog = compile("hog",
                                  "#include <stdlib.h>\n#include <string.h>\n"
                                  "int main(void) {\n"
                                  "  for (int i = 0; i < 10 * 1024; ++i) memset(malloc(1 << 20), 1, 1 << 20);\n"
                                  "  return 0;\n}\n");
  const SandboxRun run = run_of({hog});
  const SandboxResult r = run_sandboxed(run);
  EXPECT_EQ(r.end, SandboxEnd::memory) << r.reason(run.limits) << "\n" << r.output;
  EXPECT_EQ(r.signal, SIGSEGV);
  EXPECT_GE(r.peak_memory_bytes, std::uint64_t{128} << 20);
  EXPECT_LE(r.peak_memory_bytes, std::uint64_t{256} << 20);
  EXPECT_NE(r.reason(run.limits).find("ran out of memory (limit 256 MiB)"), std::string::npos) << r.reason(run.limits);

  // All 10 GiB at once: refused outright, so the crash comes before any memory is used. That is
  // told as the crash it is, with the memory limit named.
  const std::string at_once = compile("at_once",
                                      "#include <stdlib.h>\n#include <string.h>\n"
                                      "int main(void) { memset(malloc(10ul << 30), 1, 10ul << 30); return 0; }\n");
  const SandboxResult crash = run_sandboxed(run_of({at_once}));
  EXPECT_EQ(crash.end, SandboxEnd::signaled) << crash.output;
  EXPECT_EQ(crash.reason(run.limits),
            "crashed (signal 11, SIGSEGV); note that an allocation past its memory limit of 256 MiB fails");

  // A program that sees the refusal and says so exits as it chooses.
  const SandboxResult python = run_sandboxed(run_of({"python3", "-c", "x = bytearray(10 * 2**30)"}));
  EXPECT_EQ(python.end, SandboxEnd::exited) << python.output;
  EXPECT_EQ(python.exit_code, 1);
  EXPECT_NE(python.output.find("MemoryError"), std::string::npos) << python.output;
}

TEST_F(SandboxTest, WritingAGibibyteRunsOutOfFileSize) {
  const SandboxRun one_file = shell("head -c 1073741824 /dev/zero > /work/big");
  const SandboxResult big = run_sandboxed(one_file);
  EXPECT_EQ(big.end, SandboxEnd::file_size) << big.output;
  EXPECT_EQ(big.signal, SIGXFSZ);
  EXPECT_EQ(big.reason(one_file.limits), "tried to write a file larger than 64 MiB");
  EXPECT_EQ(fs::file_size(work_ / "big"), std::uintmax_t{64} << 20);

  // In 16 MiB files, each under the limit: the folder's total stops it.
  fs::remove(work_ / "big");
  const SandboxRun many = shell("i=0; while [ $i -lt 64 ]; do head -c 16777216 /dev/zero > /work/part$i; i=$((i+1)); done");
  const SandboxResult parts = run_sandboxed(many);
  EXPECT_EQ(parts.end, SandboxEnd::file_size) << parts.output;
  EXPECT_EQ(parts.signal, 0);
  EXPECT_EQ(parts.reason(many.limits), "wrote more than the 64 MiB its folders may hold");
  std::uintmax_t written = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(work_)) {
    if (entry.path().filename().string().starts_with("part")) written += entry.file_size();
  }
  EXPECT_GT(written, std::uintmax_t{64} << 20);
  EXPECT_LT(written, std::uintmax_t{640} << 20) << "stopped long after the limit";
  EXPECT_EQ(processes_left(), 0);
}

TEST_F(SandboxTest, WellBehavedProgramWritesItsFolderAndReadsItsInput) {
  ASSERT_EQ(setenv("FARM_SANDBOX_TEST_GRADER_SECRET", "grader-only", 1), 0);
  SandboxRun run = shell(
      "cat /input/in.txt > /work/out.txt && echo \"$HOME $PATH $LANG $GREETING\" >> out.txt && "
      "env > /work/env.txt && ! echo no > /input/in.txt && echo fine");
  run.environment = {{"GREETING", "hello"}};
  const SandboxResult r = run_sandboxed(run);
  unsetenv("FARM_SANDBOX_TEST_GRADER_SECRET");
  EXPECT_TRUE(r.ok()) << r.reason(run.limits) << "\n" << r.output;
  EXPECT_EQ(r.reason(run.limits), "exited with code 0");
  EXPECT_NE(r.output.find("Read-only file system"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fine\n"), std::string::npos) << r.output;
  EXPECT_EQ(read_file(work_ / "out.txt"), "the input\n/work /usr/bin:/bin C.UTF-8 hello\n");
  EXPECT_EQ(read_file(dir_ / "input/in.txt"), "the input\n");
  EXPECT_EQ(read_file(work_ / "env.txt").find("FARM_SANDBOX_TEST_GRADER_SECRET"), std::string::npos);
  // The folder and what the program made in it are the grader's again.
  struct stat info {};
  ASSERT_EQ(stat((work_ / "out.txt").c_str(), &info), 0);
  EXPECT_EQ(info.st_uid, getuid());
  ASSERT_EQ(stat(work_.c_str(), &info), 0);
  EXPECT_EQ(info.st_uid, getuid());
  EXPECT_LT(r.wall_seconds, 2.0);
}

TEST_F(SandboxTest, OutputFloodIsCutAndTheRunCompletes) {
  SandboxRun run = shell("head -c 100000000 /dev/zero | tr '\\0' x; echo; echo done");
  run.limits.output_bytes = 1000;
  const SandboxResult r = run_sandboxed(run);
  EXPECT_TRUE(r.ok()) << r.reason(run.limits);
  EXPECT_EQ(r.output, std::string(1000, 'x') + "\n[... 99999006 bytes cut]\n");
}

TEST_F(SandboxTest, WhatCannotStartIsNotTheStudentsCrash) {
  const SandboxResult missing = run_sandboxed(run_of({"/work/no-such-program"}));
  EXPECT_EQ(missing.end, SandboxEnd::failed_to_start) << missing.output;
  EXPECT_NE(missing.detail.find("/work/no-such-program: No such file or directory"), std::string::npos)
      << missing.detail;

  const SandboxResult not_in_path = run_sandboxed(run_of({"no-such-command"}));
  EXPECT_EQ(not_in_path.end, SandboxEnd::failed_to_start) << not_in_path.output;

  SandboxRun no_folder = run_of({"true"});
  no_folder.mounts.push_back({dir_ / "absent", "/absent", false});
  const SandboxResult absent = run_sandboxed(no_folder);
  EXPECT_EQ(absent.end, SandboxEnd::failed_to_start);
  EXPECT_NE(absent.reason(no_folder.limits).find("absent does not exist"), std::string::npos) << absent.detail;

  SandboxRun no_workdir = run_of({"true"});
  no_workdir.workdir = "/work/not-there";  // in a mount, so bwrap cannot make it
  const SandboxResult chdir = run_sandboxed(no_workdir);
  EXPECT_EQ(chdir.end, SandboxEnd::failed_to_start) << chdir.output;
  EXPECT_TRUE(chdir.detail.starts_with("bwrap: ")) << chdir.detail;

  const SandboxResult exit_code = run_sandboxed(shell("exit 3"));
  EXPECT_EQ(exit_code.end, SandboxEnd::exited);
  EXPECT_EQ(exit_code.exit_code, 3);
}

}  // namespace
}  // namespace farm
