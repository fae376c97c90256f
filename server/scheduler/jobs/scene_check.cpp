#include "server/scheduler/jobs/scene_check.h"

#include <fmt/format.h>
#include <malloc.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <new>
#include <optional>
#include <string_view>
#include <thread>
#include <utility>

#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/util/input_error.h"
#include "server/common/child_process.h"
#include "server/common/scene_materializer.h"
#include "server/common/service_error.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

// The child's verdict: one of these, then a space and the rest of the line.
constexpr std::string_view kVerdictPrefix = "check-scene: ";
constexpr std::string_view kPassed = "passed";
constexpr std::string_view kInvalid = "invalid";
constexpr std::string_view kOutOfMemory = "out-of-memory";
// Longest message taken from the child: the loaders' messages are a line or two.
constexpr std::size_t kMaxMessageBytes = 4096;

std::atomic<bool> g_allocation_failed{false};

// Called by operator new when an allocation fails: remembers that memory ran out (the loaders
// turn a bad_alloc into their own error message) and lets the failure through.
void note_allocation_failure() {
  g_allocation_failed = true;
  std::set_new_handler(nullptr);
  throw std::bad_alloc();
}

std::string gib(std::uint64_t bytes) { return fmt::format("{:.3g} GiB", static_cast<double>(bytes) / (1 << 30)); }

// The last verdict line in the child's output: {kind, message}, or nullopt when there is none.
std::optional<std::pair<std::string, std::string>> verdict_of(std::string_view output) {
  std::optional<std::string_view> last;
  while (!output.empty()) {
    const std::size_t end = std::min(output.find('\n'), output.size());
    const std::string_view line = output.substr(0, end);
    if (line.starts_with(kVerdictPrefix)) last = line.substr(kVerdictPrefix.size());
    output.remove_prefix(std::min(end + 1, output.size()));
  }
  if (!last) return std::nullopt;
  const std::size_t space = std::min(last->find(' '), last->size());
  const std::string_view message = last->substr(std::min(space + 1, last->size()));
  return std::pair{std::string(last->substr(0, space)),
                   std::string(message.substr(0, kMaxMessageBytes))};
}

}  // namespace

SceneChecker::SceneChecker(fs::path program, SceneBudget budget)
    : program_(std::move(program)),
      budget_(budget),
      max_parallel_(budget.max_parallel > 0 ? budget.max_parallel
                                            : std::max(1, static_cast<int>(std::thread::hardware_concurrency() / 2))) {}

void SceneChecker::acquire_slot(const std::string& display_name) {
  std::unique_lock lock(mutex_);
  if (!slot_freed_.wait_for(lock, budget_.time, [this] { return running_ < max_parallel_; })) {
    throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                       fmt::format("{}: the scheduler is checking {} other new scenes; submit again later",
                                   display_name, running_));
  }
  ++running_;
}

void SceneChecker::release_slot() {
  {
    std::lock_guard lock(mutex_);
    --running_;
  }
  slot_freed_.notify_one();
}

void SceneChecker::check(const std::string& scene_hash, const fs::path& job_file,
                         const fs::path& asset_root, const std::string& display_name) {
  if (passed_.contains(scene_hash)) return;
  acquire_slot(display_name);
  struct SlotRelease {
    SceneChecker* checker;
    ~SlotRelease() { checker->release_slot(); }
  } const slot{this};
  ChildProcess child({program_.string(), "check-scene", job_file.string(), "--asset-root",
                      asset_root.string(), "--memory-limit", std::to_string(budget_.memory_bytes)});
  std::optional<int> code = child.wait_exit(budget_.time);
  if (!code) {
    child.send_signal(SIGKILL);
    child.wait_exit(std::chrono::seconds(30));
    throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                       fmt::format("{}: loading the job's models and building its scene took longer "
                                   "than {:.4g} s, the scheduler's limit (--max-scene-seconds)",
                                   display_name, std::chrono::duration<double>(budget_.time).count()));
  }
  const auto verdict = verdict_of(child.output_to_end(std::chrono::seconds(10)));
  if (*code == 0 && verdict && verdict->first == kPassed) {
    passed_.insert(scene_hash);
    return;
  }
  if (verdict && verdict->first == kInvalid && *code == 2) {
    throw InputError(without_scene_folder(verdict->second, asset_root));
  }
  if (verdict && verdict->first == kOutOfMemory && *code == 3) {
    throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                       fmt::format("{}: loading the job's models and building its scene needs more "
                                   "than {} of memory, the scheduler's limit (--max-scene-memory): {}",
                                   display_name, gib(budget_.memory_bytes),
                                   without_scene_folder(verdict->second, asset_root)));
  }
  // A crash, or an answer out of protocol: the models are what made the child fail.
  throw InputError(fmt::format("{}: loading the job's models failed (the checking process {} "
                               "without a verdict)",
                               display_name,
                               *code > 128 ? fmt::format("died of signal {}", *code - 128)
                                           : fmt::format("exited {}", *code)));
}

int check_scene_in_this_process(const fs::path& job_file, const fs::path& asset_root,
                                std::uint64_t memory_bytes) {
  // Gone with the scheduler, even when it is killed or abandons the call at shutdown.
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() == 1) return 1;
  // A few malloc arenas, not eight per core: their reserved address space counts against the
  // limit although nothing uses it.
  mallopt(M_ARENA_MAX, 2);
  const rlimit memory{memory_bytes, memory_bytes};
  const rlimit no_core{0, 0};
  if (setrlimit(RLIMIT_AS, &memory) != 0 || setrlimit(RLIMIT_CORE, &no_core) != 0) {
    std::perror("check-scene: setrlimit");
    return 1;
  }
  std::set_new_handler(note_allocation_failure);
  auto say = [](std::string_view kind, const std::string& message) {
    std::string line = message;
    for (char& c : line)
      if (c == '\n' || c == '\r') c = ' ';
    std::fprintf(stdout, "%.*s%.*s %s\n", static_cast<int>(kVerdictPrefix.size()), kVerdictPrefix.data(),
                 static_cast<int>(kind.size()), kind.data(), line.c_str());
    std::fflush(stdout);
  };
  try {
    JobLoadOptions options;
    options.asset_root = asset_root;
    const Job job = load_job(job_file, options);
    const Scene scene = build_scene(job);
    say(kPassed, "");
    return 0;
  } catch (const std::bad_alloc& e) {
    say(kOutOfMemory, e.what());
    return 3;
  } catch (const InputError& e) {
    if (g_allocation_failed) {
      say(kOutOfMemory, e.what());
      return 3;
    }
    say(kInvalid, e.what());
    return 2;
  } catch (const std::exception& e) {
    say(g_allocation_failed ? kOutOfMemory : kInvalid, e.what());
    return g_allocation_failed ? 3 : 2;
  }
}

}  // namespace farm
