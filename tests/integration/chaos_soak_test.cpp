// The chaos soak (issue #16, item 7): 40 jobs of every engine through a real `farm scheduler` and
// three `farm worker`s that register with it, while the test kills -9 or SIGSTOPs a random worker
// every 1-3 s (a killed one is restarted on its cache, a stopped one continued after a while), and
// kills -9 the scheduler once and SIGTERMs it once, each time restarting it on the same data dir
// and port. With the scheduler's default --max-attempts every job must SUCCEED, bit-identical to
// `farm render` of its job file; no tile result is accepted twice; and the renderings the store
// records as lost (its tile failures, every one rendered again) are no more than the units the
// store showed running on the victims around their kills and stops.
//
// The random choices come from a fixed seed, printed, so a failure replays the same schedule of
// victims and signals (the timing between processes of course varies). Every wait is bounded and
// polls for what it waits for; the pauses between chaos events only pace the chaos, and nothing
// depends on their length.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "renderer/image/exr_io.h"
#include "server/common/job_state.h"
#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/run_command.h"
#include "tests/support/running_tiles.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr std::uint32_t kSeed = 20261116;  // the chaos schedule: change it to explore another
constexpr int kJobs = 40;
constexpr int kWorkers = 3;
// Heartbeats every 0.5 s: a worker silent for 1.5 s (a SIGSTOP longer than that) is dropped.
constexpr const char* kHeartbeatSeconds = "0.5";
// The scheduler is killed -9 once this many jobs are final, and SIGTERMed at the second number:
// by progress, not by time, so both land while work remains whatever the machine's speed.
constexpr int kKillSchedulerAt = 10;
constexpr int kStopSchedulerAt = 22;
// Bounds, generous: nothing here is a speed requirement.
constexpr auto kSoakTimeout = 420s;
constexpr auto kStartTimeout = 30s;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Job i of the soak: the Cornell box, engines in turn, 64 to 96 pixels square in tiles of 16 or
// 32 (9 to 36 tiles, so that units are in flight at every kill), each job its own seed and spp.
nlohmann::json soak_job(int i) {
  static constexpr std::array<const char*, 3> kEngines{"raster", "whitted", "path"};
  const std::string engine = kEngines[static_cast<std::size_t>(i % 3)];
  const int size = 64 + 16 * ((i / 3) % 3);
  const int spp = engine == "path" ? 200 + 16 * (i / 3) : 1 + (i / 3) % 4;
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json(engine, size, size, spp));
  job["name"] = "soak-" + std::to_string(i);
  job["render"]["tile_size"] = i % 2 == 0 ? 16 : 32;
  job["render"]["seed"] = i;
  return job;
}

class ChaosSoak : public ::testing::Test {
 protected:
  // `farm scheduler` on `listen` over the soak's data dir; false (with the reason recorded) when
  // it does not come up.
  bool start_scheduler(const std::string& listen) {
    scheduler_ = std::make_unique<test::BackgroundProcess>(std::vector<std::string>{
        FARM_BINARY, "scheduler", "--listen", listen, "--data-dir", (dir_ / "data").string(),
        "--heartbeat-interval", kHeartbeatSeconds});
    address_ = wait_for_listening(*scheduler_, "scheduler", kStartTimeout);
    if (address_.empty()) {
      ADD_FAILURE() << "the scheduler did not start on " << listen << ": " << scheduler_->output();
      return false;
    }
    stub_ = test::scheduler_stub(address_);
    return true;
  }

  // Worker `k` (1-based cache folder wK), registered with the scheduler.
  bool start_worker(std::size_t k) {
    // Appended, not "w" + to_string(): GCC 12 sees a false -Wrestrict in the latter.
    std::string cache = "w";
    cache += std::to_string(k + 1);
    workers_[k] = std::make_unique<test::WorkerProcess>(
        std::vector<std::string>{"--threads", "1", "--cache-dir", (dir_ / cache).string(), "--scheduler", address_});
    if (workers_[k]->address().empty() ||
        !workers_[k]->process().wait_for_line("registered with the scheduler", kStartTimeout)) {
      ADD_FAILURE() << "worker " << k + 1 << " did not start and register: " << workers_[k]->process().output();
      return false;
    }
    return true;
  }

  // The jobs as the scheduler has them now; the ones it could not answer for are left out (it
  // may be down for a moment).
  std::map<std::string, v1::Job> poll_jobs() const {
    std::map<std::string, v1::Job> jobs;
    for (const std::string& id : job_ids_) {
      if (const std::optional<v1::Job> job = test::get_job(*stub_, id)) jobs[id] = *job;
    }
    return jobs;
  }

  int final_jobs() const {
    int n = 0;
    for (const auto& [id, job] : poll_jobs()) n += is_final(job.state()) ? 1 : 0;
    return n;
  }

  // Adds to `seen` what the store shows running on `address` until `done()`, looked at every
  // millisecond or so: a unit handed to the victim and lost again between two looks would go
  // uncounted.
  void watch_running(const std::string& address, std::set<test::Unit>& seen, const std::function<bool()>& done) {
    const auto end = Clock::now() + 60s;
    while (!done() && Clock::now() < end) {
      const std::set<test::Unit> now = running_->on_worker(address);
      seen.insert(now.begin(), now.end());
      std::this_thread::sleep_for(1ms);
    }
  }

  static int occurrences(const std::string& text, const std::string& needle) {
    int n = 0;
    for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
    return n;
  }

  // Whether the scheduler running now holds no entry for a worker at `address`: every one it
  // added (log line "worker w<N>-<address> added") it has dropped ("... removed: ..."), after
  // which no slot hands that worker anything.
  bool scheduler_let_go(const std::string& address) const {
    const std::string log = scheduler_->output();
    return occurrences(log, "-" + address + " added") <= occurrences(log, "-" + address + " removed");
  }

  // Waits until every worker has registered with the scheduler started last (each prints
  // "registered with the scheduler" once more than `before` says).
  bool workers_registered_again(const std::array<int, kWorkers>& before) {
    for (std::size_t k = 0; k < kWorkers; ++k) {
      const auto end = Clock::now() + 60s;
      while (registrations(k) <= before[k]) {
        if (Clock::now() > end) {
          ADD_FAILURE() << "worker " << k + 1 << " did not register with the restarted scheduler: "
                        << workers_[k]->process().output();
          return false;
        }
        std::this_thread::sleep_for(10ms);
      }
    }
    return true;
  }
  int registrations(std::size_t k) const {
    return occurrences(workers_[k]->process().output(), "registered with the scheduler");
  }
  std::array<int, kWorkers> all_registrations() const {
    std::array<int, kWorkers> n{};
    for (std::size_t k = 0; k < kWorkers; ++k) n[k] = registrations(k);
    return n;
  }

  // The scheduler that just exited: its log kept for the report.
  void keep_scheduler_log() { scheduler_logs_ += scheduler_->output_to_end(10s); }

  test::TempDir dir_;
  std::unique_ptr<test::BackgroundProcess> scheduler_;
  std::string address_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
  std::array<std::unique_ptr<test::WorkerProcess>, kWorkers> workers_;
  std::unique_ptr<test::RunningTiles> running_;
  std::vector<std::string> job_ids_;
  std::string scheduler_logs_;  // of the schedulers that exited
};

TEST_F(ChaosSoak, FortyJobsSurviveWorkersKilledAndStoppedAndTwoSchedulerRestarts) {
  const Clock::time_point start = Clock::now();
  std::cout << "[ chaos    ] seed " << kSeed << std::endl;
  std::mt19937 rng(kSeed);

  ASSERT_TRUE(start_scheduler("127.0.0.1:0"));
  const std::string listen = address_;  // restarts come back here, where the workers look
  running_ = std::make_unique<test::RunningTiles>(dir_ / "data" / "jobs.db");
  for (std::size_t k = 0; k < kWorkers; ++k) ASSERT_TRUE(start_worker(k));

  // Every job file, written as `farm render` reads it, and submitted.
  std::vector<fs::path> job_files;
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  for (int i = 0; i < kJobs; ++i) {
    const std::string json = soak_job(i).dump(2);
    const fs::path job_dir = dir_ / "jobs" / std::to_string(i);
    fs::create_directories(job_dir / "assets");
    for (const auto& [path, file] : test::cornell_assets()) fs::copy_file(file, job_dir / path);
    std::ofstream(job_dir / "cornell.json") << json;
    job_files.push_back(job_dir / "cornell.json");
    v1::Job job;
    const grpc::Status status =
        test::submit(*stub_, test::make_job_spec(json, test::cornell_assets(), "cornell.json"), job);
    ASSERT_TRUE(status.ok()) << "job " << i << ": " << status.error_message();
    job_ids_.push_back(job.job_id());
  }

  // The references render beside the farm, one `farm render` at a time: more load on the same
  // cores, which only stretches the soak.
  std::vector<test::CommandResult> references(kJobs);
  std::thread reference_renders([&] {
    for (int i = 0; i < kJobs; ++i) {
      const fs::path out = dir_ / "references" / (std::to_string(i) + ".exr");
      references[static_cast<std::size_t>(i)] = test::run_command(test::farm_command(
          "render " + test::shell_quote(job_files[static_cast<std::size_t>(i)].string()) + " --quiet --out " +
          test::shell_quote(out.string()) + " --preview none"));
    }
  });
  struct JoinReferences {
    std::thread& t;
    ~JoinReferences() {
      if (t.joinable()) t.join();
    }
  } join_references{reference_renders};

  // The chaos, until every job is final.
  std::size_t in_flight_at_worker_events = 0, in_flight_at_scheduler_events = 0;
  std::map<std::string, std::size_t> in_flight_by_address;  // each victim's units, over its events
  int worker_kills = 0, worker_stops = 0;
  bool scheduler_killed = false, scheduler_stopped = false;
  std::uniform_int_distribution<int> pause_ms(1000, 3000), stop_ms(500, 3000), victim(0, kWorkers - 1);
  std::bernoulli_distribution kill_it(0.5);
  int final_now = 0;
  while ((final_now = final_jobs()) < kJobs) {
    ASSERT_LT(seconds_since(start), std::chrono::duration<double>(kSoakTimeout).count())
        << final_now << " of " << kJobs << " jobs final; the scheduler said: " << scheduler_->output();
    std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms(rng)));

    if (!scheduler_killed && final_now >= kKillSchedulerAt) {
      scheduler_->send_signal(SIGKILL);
      ASSERT_TRUE(scheduler_->wait_exit(10s).has_value()) << "the scheduler outlived SIGKILL";
      // What the dead scheduler had in flight: the next one queues it again (no failure counted).
      const std::size_t running = running_->all().size();
      in_flight_at_scheduler_events += running;
      std::cout << "[ chaos    ] " << seconds_since(start) << " s: kill -9 the scheduler (" << final_now
                << " jobs final, " << running << " units in flight)" << std::endl;
      scheduler_killed = true;
      keep_scheduler_log();
      const std::array<int, kWorkers> registered = all_registrations();
      ASSERT_TRUE(start_scheduler(listen));
      ASSERT_TRUE(workers_registered_again(registered));
      continue;
    }
    if (!scheduler_stopped && final_now >= kStopSchedulerAt) {
      // Looked at just before the signal: the scheduler queues its calls' tiles again as it stops.
      const std::size_t running = running_->all().size();
      scheduler_->send_signal(SIGTERM);
      const std::optional<int> code = scheduler_->wait_exit(10s);
      ASSERT_TRUE(code) << "the scheduler did not stop on SIGTERM: " << scheduler_->output();
      EXPECT_EQ(*code, 0) << scheduler_->output();
      in_flight_at_scheduler_events += running;
      std::cout << "[ chaos    ] " << seconds_since(start) << " s: SIGTERM the scheduler (" << final_now
                << " jobs final, " << running << " units in flight)" << std::endl;
      scheduler_stopped = true;
      keep_scheduler_log();
      const std::array<int, kWorkers> registered = all_registrations();
      ASSERT_TRUE(start_scheduler(listen));
      ASSERT_TRUE(workers_registered_again(registered));
      continue;
    }

    const std::size_t k = static_cast<std::size_t>(victim(rng));
    const std::string address = workers_[k]->address();
    std::set<test::Unit> in_flight = running_->on_worker(address);
    if (kill_it(rng)) {
      workers_[k]->process().send_signal(SIGKILL);
      // Until the scheduler has dropped the dead worker (its heartbeats stopped) and taken back
      // everything it held: a slot of it that was between calls at the kill may still hand it a
      // batch before then, which is lost too.
      int looks = 0;
      watch_running(address, in_flight, [&] {
        return ++looks % 25 == 0 && scheduler_let_go(address) && running_->on_worker(address).empty();
      });
      ASSERT_TRUE(workers_[k]->process().wait_exit(10s).has_value()) << "worker " << k + 1 << " outlived SIGKILL";
      ++worker_kills;
      std::cout << "[ chaos    ] " << seconds_since(start) << " s: kill -9 worker " << k + 1 << " (" << address
                << "): " << in_flight.size() << " units in flight" << std::endl;
      ASSERT_TRUE(start_worker(k));
    } else {
      const auto hold = std::chrono::milliseconds(stop_ms(rng));
      workers_[k]->process().send_signal(SIGSTOP);
      const Clock::time_point stopped = Clock::now();
      watch_running(address, in_flight, [&] { return Clock::now() - stopped >= hold; });
      workers_[k]->process().send_signal(SIGCONT);
      // Until what it held has left it, answered or taken back: the scheduler may still drop it
      // after the continue, before it has been heard from, with what it holds then.
      const std::set<test::Unit> held = in_flight;
      watch_running(address, in_flight, [&] {
        const std::set<test::Unit> now = running_->on_worker(address);
        return std::none_of(held.begin(), held.end(), [&](const test::Unit& u) { return now.contains(u); });
      });
      ++worker_stops;
      std::cout << "[ chaos    ] " << seconds_since(start) << " s: SIGSTOP worker " << k + 1 << " (" << address
                << ") for " << hold.count() << " ms: " << in_flight.size() << " units in flight" << std::endl;
    }
    in_flight_at_worker_events += in_flight.size();
    in_flight_by_address[address] += in_flight.size();
  }
  ASSERT_TRUE(scheduler_killed && scheduler_stopped)
      << "the jobs were done before both scheduler restarts: the soak's jobs are too light for it";

  // Every job SUCCEEDED, each tile's result accepted once.
  const std::map<std::string, v1::Job> jobs = poll_jobs();
  ASSERT_EQ(jobs.size(), static_cast<std::size_t>(kJobs));
  std::uint64_t lost_renderings = 0, tiles_total = 0;
  for (int i = 0; i < kJobs; ++i) {
    const v1::Job& job = jobs.at(job_ids_[static_cast<std::size_t>(i)]);
    EXPECT_EQ(job.state(), v1::JOB_STATE_SUCCEEDED) << "job " << i << ": " << job.failure_reason();
    EXPECT_EQ(job.tiles_done(), job.tiles_total()) << "job " << i;
    // Nothing that was done was rendered and accepted again, across the kills and the restarts.
    EXPECT_EQ(job.tiles_rendered(), job.tiles_total()) << "job " << i;
    lost_renderings += job.tile_failures();
    tiles_total += job.tiles_total();
  }

  // Bit-identical to `farm render`, every channel.
  reference_renders.join();
  for (int i = 0; i < kJobs; ++i) {
    const test::CommandResult& r = references[static_cast<std::size_t>(i)];
    ASSERT_EQ(r.exit_code, 0) << "farm render of job " << i << ": " << r.output;
    const fs::path fetched = dir_ / "fetched" / (std::to_string(i) + ".exr");
    fs::create_directories(fetched.parent_path());
    const grpc::Status status =
        test::fetch_result(*stub_, job_ids_[static_cast<std::size_t>(i)], v1::RESULT_KIND_EXR, fetched);
    ASSERT_TRUE(status.ok()) << "job " << i << ": " << status.error_message();
    EXPECT_EQ(test::differing_pixels(read_exr(fetched), read_exr(dir_ / "references" / (std::to_string(i) + ".exr"))),
              0)
        << "job " << i << " (" << soak_job(i)["render"].dump() << ")";
  }

  // Lost renderings (each rendered again) no more than what was in flight on the victims.
  std::cout << "[ chaos    ] " << kJobs << " jobs, " << tiles_total << " tiles; " << worker_kills
            << " workers killed -9, " << worker_stops << " stopped; scheduler killed -9 and SIGTERMed\n"
            << "[ chaos    ] Re-renders / units in flight " << lost_renderings << "/" << in_flight_at_worker_events
            << " (worker kills and stops; the store's tile failures against the units it showed running on "
               "the victims)\n"
            << "[ chaos    ] units in flight at the scheduler's kill -9 and SIGTERM, queued again by the next "
               "scheduler: "
            << in_flight_at_scheduler_events << "\n"
            << "[ chaos    ] duration " << seconds_since(start) << " s" << std::endl;
  // The scheduler's own account of each lost rendering, by the worker it was lost with: no
  // worker may have lost more than the test saw in flight on it when it killed or stopped it (a
  // healthy worker dropped, or a rendering failed for any other reason, would show here).
  scheduler_logs_ += scheduler_->output();
  std::string failure_lines;
  std::map<std::string, std::size_t> lost_by_address;
  std::istringstream log(scheduler_logs_);
  for (std::string line; std::getline(log, line);) {
    // spdlog names the level "warning" (server/common/log.cpp's pattern).
    if (line.find("[warning] job ") == std::string::npos) continue;
    failure_lines += line + "\n";
    const std::size_t tiles_at = line.find(" unit"), worker_at = line.find(": worker ");
    if (tiles_at == std::string::npos || worker_at == std::string::npos) continue;
    // "job ID unit N: worker ADDR ..." or "job ID units A-B: worker ADDR ...".
    unsigned first = 0, last = 0;
    std::size_t count = 1;
    if (std::sscanf(line.c_str() + tiles_at, " units %u-%u", &first, &last) == 2) count = last - first + 1;
    // The address (HOST:PORT) ends at a space (" left: ...") or at ": " (": UNAVAILABLE: ...").
    std::size_t end = worker_at + 9;
    while (end < line.size() && line[end] != ' ' && !(line[end] == ':' && end + 1 < line.size() && line[end + 1] == ' ')) {
      ++end;
    }
    lost_by_address[line.substr(worker_at + 9, end - (worker_at + 9))] += count;
  }
  // Each lost rendering has its line: a log that stopped matching would make the check below empty.
  std::size_t lost_in_log = 0;
  for (const auto& [address, lost] : lost_by_address) lost_in_log += lost;
  EXPECT_GE(lost_in_log, lost_renderings) << "the scheduler's log names fewer lost renderings than the store counts:\n"
                                          << failure_lines;
  for (const auto& [address, lost] : lost_by_address) {
    EXPECT_LE(lost, in_flight_by_address[address]) << "renderings lost with worker " << address << ":\n"
                                                    << failure_lines;
  }
  EXPECT_LE(lost_renderings, in_flight_at_worker_events) << failure_lines;
  EXPECT_GT(worker_kills + worker_stops, 0);
}

}  // namespace
}  // namespace farm
