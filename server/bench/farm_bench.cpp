#include "server/bench/farm_bench.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/util/input_error.h"
#include "server/bench/bench_support.h"
#include "server/bench/loopback_farm.h"
#include "server/client/job_submission.h"
#include "server/client/scheduler_client.h"
#include "server/common/child_process.h"
#include "server/embedded/embedded_farm.h"
#include "server/scheduler/jobs/tile_results.h"
#include "server/scheduler/store/postgres_connection.h"

namespace farm {
namespace {

using bench::median;
using bench::seconds_since;
using bench::self_binary;

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;


// Submit, follow to the end, fetch the EXR: what `farm submit --wait` does.
double render_through(SchedulerClient& client, const JobSubmission& submission, const fs::path& out) {
  const Clock::time_point start = Clock::now();
  const v1::Job job = bench::submit_and_wait(client, submission).first;
  client.fetch(job.job_id(), v1::RESULT_KIND_EXR, [&](const std::string&) { return out; });
  return seconds_since(start);
}

// (a), (b) and (c) on the same job; the farms of (b) and (c) are stopped on return.
void compare_setups(const FarmBenchOptions& o, const fs::path& dir, const JobSubmission& submission) {
  // The three set-ups take turns, (a) (b) (c) (a) (b) (c) ..., so that a change in the machine's
  // load during the run (it is shared) falls on all three alike; the medians are compared.
  bench::LoopbackFarm one(dir / "loopback1", 1, o.tiles_per_worker, o.batch_ms, 0);
  bench::LoopbackFarm two(dir / "loopback2", 2, o.tiles_per_worker, o.batch_ms, o.two_worker_threads);
  SchedulerClient client_one(one.address()), client_two(two.address());
  std::vector<double> embedded, one_worker, two_workers;
  for (int i = 0; i < o.repeats; ++i) {
    const Clock::time_point start = Clock::now();
    EmbeddedFarmOptions embedded_options;
    embedded_options.batch_target = std::chrono::milliseconds(o.batch_ms);
    EmbeddedFarm farm(embedded_options);
    // As `farm render` runs it: the models loaded in this process, the EXR and preview written
    // to the job's outputs.
    JobSubmission local = submission;
    local.job.output.image = dir / "embedded.exr";
    local.job.output.preview = dir / "embedded.png";
    const EmbeddedResult r = farm.run_local(local);
    if (r.job.state() != v1::JOB_STATE_SUCCEEDED) throw std::runtime_error("embedded render failed: " + r.job.failure_reason());
    embedded.push_back(seconds_since(start));
    one_worker.push_back(render_through(client_one, submission, dir / "loopback.exr"));
    two_workers.push_back(render_through(client_two, submission, dir / "loopback.exr"));
  }
  const double a = median(embedded), b = median(one_worker), c = median(two_workers);
  // Paired by round: the three runs of a round are seconds apart, so their ratio sees the same
  // machine; the median of those ratios is the steadiest figure on a shared machine.
  std::vector<double> b_over_a, b_over_c;
  for (int i = 0; i < o.repeats; ++i) {
    b_over_a.push_back(one_worker[i] / embedded[i]);
    b_over_c.push_back(one_worker[i] / two_workers[i]);
  }
  const auto best = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
  fmt::print("{:<44} {:>8} {:>8}\n", "", "median", "best");
  fmt::print("{:<44} {:>8.3f} {:>8.3f} s\n", "(a) farm render (embedded farm)", a, best(embedded));
  fmt::print("{:<44} {:>8.3f} {:>8.3f} s   {:+.1f}% vs (a) (best: {:+.1f}%)\n", "(b) scheduler + 1 worker over loopback",
             b, best(one_worker), 100.0 * (b - a) / a, 100.0 * (best(one_worker) - best(embedded)) / best(embedded));
  fmt::print("{:<44} {:>8.3f} {:>8.3f} s   {:+.1f}% vs (a), {:.2f}x the speed of (b) (best: {:.2f}x)\n",
             "(c) scheduler + 2 workers over loopback", c, best(two_workers), 100.0 * (c - a) / a, b / c,
             best(one_worker) / best(two_workers));
  fmt::print("paired by round (median of {} rounds): (b) {:+.1f}% vs (a); (c) {:.2f}x the speed of (b)\n", o.repeats,
             100.0 * (median(b_over_a) - 1.0), median(b_over_c));
}

// Tiny jobs: one 16x16 tile each, submitted back to back to `schedulers` schedulers on `store`
// (taking turns; one data dir), each with one registered worker, then followed to the end:
// jobs/s and units/s (a tiny job is one unit), submit latency, and none lost.
void run_tiny_jobs(const FarmBenchOptions& o, const fs::path& dir, const std::string& label, const std::string& store,
                   int schedulers) {
  std::vector<std::unique_ptr<bench::LoopbackFarm>> farms;
  std::vector<std::unique_ptr<SchedulerClient>> clients;
  for (int i = 0; i < schedulers; ++i) {
    farms.push_back(std::make_unique<bench::LoopbackFarm>(dir / fmt::format("scheduler{}", i), 1, o.tiles_per_worker,
                                                          o.batch_ms, 0, store, dir / "data"));
    clients.push_back(std::make_unique<SchedulerClient>(farms.back()->address()));
  }
  RenderOverrides tiny;
  tiny.engine = "raster";
  tiny.width = 16;
  tiny.height = 16;
  tiny.spp = 1;
  tiny.preview = fs::path();
  const JobSubmission small = make_job_submission(o.job, {}, tiny);
  clients.front()->upload_missing(small);
  std::vector<std::pair<SchedulerClient*, std::string>> ids;
  std::vector<double> latency_ms;
  const Clock::time_point start = Clock::now();
  for (int i = 0; i < o.tiny_jobs; ++i) {
    SchedulerClient& client = *clients[static_cast<std::size_t>(i % schedulers)];
    const Clock::time_point t = Clock::now();
    client.upload_missing(small);  // as `farm submit` does: one HasAssets, nothing to upload
    ids.emplace_back(&client, client.submit(small, 0).job_id());
    latency_ms.push_back(1e3 * seconds_since(t));
  }
  const double submitted_s = seconds_since(start);
  int succeeded = 0;
  std::uint64_t units = 0;
  for (const auto& [client, id] : ids) {
    const v1::Job job = client->watch(id, {});
    succeeded += job.state() == v1::JOB_STATE_SUCCEEDED ? 1 : 0;
    units += job.tiles_done();
  }
  const double total_s = seconds_since(start);
  std::sort(latency_ms.begin(), latency_ms.end());
  fmt::print("{} tiny jobs (16x16 raster) on {}, {} scheduler{} with a worker each: submitted in {:.3f} s, all "
             "finished after {:.3f} s: {:.0f} jobs/s, {:.0f} units/s; {} succeeded, {} lost or failed\n",
             o.tiny_jobs, label, schedulers, schedulers == 1 ? "" : "s", submitted_s, total_s, o.tiny_jobs / total_s,
             static_cast<double>(units) / total_s, succeeded, o.tiny_jobs - succeeded);
  fmt::print("  submit latency: median {:.2f} ms, p99 {:.2f} ms, max {:.2f} ms\n", latency_ms[latency_ms.size() / 2],
             latency_ms[std::min(latency_ms.size() - 1, latency_ms.size() * 99 / 100)], latency_ms.back());
  if (succeeded != o.tiny_jobs) {
    throw std::runtime_error(fmt::format("{} tiny jobs on {} did not succeed", o.tiny_jobs - succeeded, label));
  }
}

// Where the schedulers of one farm keep the units' results (issue #18, item 2): files in the data
// dir they share (TileResults, as the scheduler writes and reads them) against bytea rows in the
// PostgreSQL store. Each way writes `count` results of a 32x32 path-traced tile with its AOVs,
// then reads them all back; neither waits for its disk (the store marks units done with
// unflushed commits, the files are not fsynced).
void compare_result_storage(const std::string& store, const fs::path& dir, int count) {
  constexpr int kEdge = 32;
  constexpr int kPixels = kEdge * kEdge;
  std::mt19937 random(7);
  const auto noise = [&](int floats) {
    std::string bytes(static_cast<std::size_t>(floats) * 4, '\0');
    for (char& c : bytes) c = static_cast<char>(random());  // pixels do not compress
    return bytes;
  };
  v1::RenderTileResponse result;
  v1::TileData& tile = *result.mutable_tile();
  tile.set_width(kEdge);
  tile.set_height(kEdge);
  tile.set_rgba(noise(4 * kPixels));
  tile.set_depth(noise(kPixels));
  tile.set_normal(noise(3 * kPixels));
  tile.set_albedo(noise(3 * kPixels));
  tile.set_variance(noise(3 * kPixels));
  const std::string bytes = result.SerializeAsString();
  const double mib = static_cast<double>(bytes.size()) * count / (1 << 20);

  const TileResults files(dir / "tiles");
  Clock::time_point t = Clock::now();
  for (int i = 0; i < count; ++i) files.write("bench", static_cast<std::uint32_t>(i), result);
  const double file_write_s = seconds_since(t);
  t = Clock::now();
  for (int i = 0; i < count; ++i) {
    if (files.read("bench", static_cast<std::uint32_t>(i)).tile().rgba().size() != tile.rgba().size()) {
      throw std::runtime_error("a result file read back differs");
    }
  }
  const double file_read_s = seconds_since(t);

  PostgresConnection db(store);
  db.exec("SET synchronous_commit TO OFF");
  db.exec("CREATE TEMPORARY TABLE bench_results (part bigint PRIMARY KEY, data bytea NOT NULL)");
  t = Clock::now();
  for (int i = 0; i < count; ++i) {
    Query(db.prepared("INSERT INTO bench_results (part, data) VALUES (?, ?)")).bind(1, i).bind_blob(2, bytes).run();
  }
  const double db_write_s = seconds_since(t);
  t = Clock::now();
  for (int i = 0; i < count; ++i) {
    Query q(db.prepared("SELECT data FROM bench_results WHERE part = ?"));
    q.bind(1, i);
    if (!q.step() || q.blob(0) != bytes) throw std::runtime_error("a result row read back differs");
  }
  const double db_read_s = seconds_since(t);
  fmt::print("unit results ({} of {:.0f} KiB, a 32x32 tile with its AOVs): shared data dir write {:.0f} MiB/s, read "
             "{:.0f} MiB/s; PostgreSQL bytea write {:.0f} MiB/s, read {:.0f} MiB/s (files {:.1f}x and {:.1f}x)\n",
             count, static_cast<double>(bytes.size()) / 1024, mib / file_write_s, mib / file_read_s, mib / db_write_s,
             mib / db_read_s, db_write_s / file_write_s, db_read_s / file_read_s);
}

}  // namespace

void run_farm_bench(const FarmBenchOptions& o) {
  const bench::ScratchDir scratch("bench");
  const fs::path& dir = scratch.path();

  RenderOverrides overrides;
  overrides.width = o.width;
  overrides.height = o.height;
  overrides.spp = o.spp;
  const JobSubmission submission = make_job_submission(o.job, {}, overrides);
  fmt::print("farm bench farm ({}): {} at {}x{}, {} spp, {} tiles of {} px, "
             "median of {}\n", bench::machine_summary(), o.job.string(), o.width,
             o.height, o.spp, (o.width + submission.job.render.tile_size - 1) / submission.job.render.tile_size *
                 ((o.height + submission.job.render.tile_size - 1) / submission.job.render.tile_size),
             submission.job.render.tile_size, o.repeats);

  compare_setups(o, dir, submission);
  // The files the renders wrote are flushed first, so that their write-back does not stall the
  // tiny jobs' database commits.
  ::sync();

  run_tiny_jobs(o, dir / "tiny-sqlite", "SQLite", {}, 1);
  if (!o.store.empty()) {
    run_tiny_jobs(o, dir / "tiny-postgresql-1", "PostgreSQL", o.store, 1);
    run_tiny_jobs(o, dir / "tiny-postgresql-2", "PostgreSQL", o.store, 2);
    compare_result_storage(o.store, dir / "results", 500);
  }
}

}  // namespace farm
