// Starts the real `farm scheduler` and `farm worker` binaries on loopback and drives them through
// the generated farm.v1.Scheduler stub: results bit-identical to `farm render`, workers and the
// scheduler killed mid-job, cancellation, bad jobs. Every wait is bounded; nothing sleeps blind.
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <future>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <thread>
#include <tuple>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/exr_io.h"
#include "renderer/job/job.h"
#include "renderer/job/job_limits.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "server/common/asset_store.h"
#include "server/common/sha256.h"
#include "tests/support/background_process.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"
#include "tests/support/postgres_server.h"
#include "tests/support/run_command.h"
#include "tests/support/running_tiles.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/store_locations.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

namespace fs = std::filesystem;
using namespace std::chrono_literals;

bool done(const v1::Job& job) {
  return job.state() == v1::JOB_STATE_SUCCEEDED || job.state() == v1::JOB_STATE_FAILED ||
         job.state() == v1::JOB_STATE_CANCELLED;
}

// The Cornell box with a render block of our choosing.
v1::JobSpec cornell(const std::string& engine, int width, int height, int spp, int tile_size) {
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json(engine, width, height, spp));
  job["render"]["tile_size"] = tile_size;
  return test::make_job_spec(job.dump(2), test::cornell_assets(), "cornell.json");
}

TileBuffer render_locally(const v1::JobSpec& spec) {
  const Job job = parse_job(spec.job_json(), test::kSource / "jobs" / spec.file_name());
  const PreparedScene scene(build_scene(job));
  return render_frame(scene, job.render);
}

int differing_pixels(const TileBuffer& a, const TileBuffer& b) {
  if (!(a.rect() == b.rect())) return -1;
  int differing = 0;
  for (int y = a.rect().y0; y < a.rect().y1; ++y) {
    for (int x = a.rect().x0; x < a.rect().x1; ++x) {
      if (std::memcmp(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)) != 0 ||
          (a.aovs().has(Aov::Depth) && !same_bits(a.depth(x, y), b.depth(x, y))) ||
          (a.aovs().has(Aov::Normal) &&
           std::memcmp(&a.normal(x, y), &b.normal(x, y), sizeof(glm::vec3)) != 0) ||
          (a.aovs().has(Aov::Albedo) &&
           std::memcmp(&a.albedo(x, y), &b.albedo(x, y), sizeof(glm::vec3)) != 0) ||
          (a.aovs().has(Aov::Variance) &&
           std::memcmp(&a.variance(x, y), &b.variance(x, y), sizeof(glm::vec3)) != 0)) {
        ++differing;
      }
    }
  }
  return differing;
}

// The last line of `output` that is a JSON object (the Python checks print their result last).
nlohmann::json last_json_line(const std::string& output) {
  const std::size_t line = output.rfind("\n{");
  return nlohmann::json::parse(output.substr(line == std::string::npos ? 0 : line + 1));
}

class FarmSchedulerTest : public ::testing::Test {
 protected:
  // A worker whose cache already holds the Cornell box's files (so a static --worker needs no
  // way to fetch them), or one that registers with `scheduler` and fetches from it.
  std::unique_ptr<test::WorkerProcess> start_worker(const std::string& name, int threads = 1,
                                                    const std::string& scheduler = "") {
    std::vector<std::string> args{"--threads", std::to_string(threads), "--cache-dir",
                                  (dir_ / name).string()};
    if (scheduler.empty()) {
      const AssetStore blobs(dir_ / name / "blobs");
      for (const auto& [path, file] : test::cornell_assets()) blobs.add(test::read_file(file));
    } else {
      args.insert(args.end(), {"--scheduler", scheduler});
    }
    auto worker = std::make_unique<test::WorkerProcess>(args);
    EXPECT_FALSE(worker->address().empty()) << worker->process().output();
    if (!scheduler.empty()) {
      EXPECT_TRUE(worker->process().wait_for_line("registered with the scheduler", 20s))
          << worker->process().output();
    }
    return worker;
  }

  std::unique_ptr<test::SchedulerProcess> start_scheduler(std::vector<std::string> args) {
    // A restarted scheduler on a shared store renders its predecessor's units once its lease ran
    // out: short here, so that tests wait seconds, not the default ten.
    if (!store_.empty()) args.insert(args.end(), {"--store", store_, "--lease", "2"});
    auto scheduler = std::make_unique<test::SchedulerProcess>(dir_ / "data", args);
    EXPECT_FALSE(scheduler->address().empty()) << scheduler->process().output();
    if (!store_.empty()) {
      EXPECT_TRUE(scheduler->process().wait_for_line("job store postgresql://", 10s)) << scheduler->process().output();
    }
    if (!scheduler->address().empty()) stub_ = test::scheduler_stub(scheduler->address());
    return scheduler;
  }

  v1::Job submit_ok(const v1::JobSpec& spec) {
    EXPECT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
    v1::Job job;
    const grpc::Status status = test::submit(*stub_, spec, job);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return job;
  }

  // CancelJob through stub_; the job as the scheduler answered.
  v1::Job cancel_ok(const std::string& id) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 10s);
    v1::CancelJobRequest request;
    request.set_job_id(id);
    v1::CancelJobResponse response;
    const grpc::Status call = stub_->CancelJob(&context, request, &response);
    EXPECT_TRUE(call.ok()) << call.error_code() << ": " << call.error_message();
    EXPECT_EQ(response.job().state(), v1::JOB_STATE_CANCELLED);
    return response.job();
  }

  // Submits `spec`, sends `signal` to `victim` once a few tiles are done, and returns the job
  // once it is final (nullopt when it never gets there).
  std::optional<v1::Job> signal_worker_mid_job(const v1::JobSpec& spec, test::WorkerProcess& victim,
                                               int signal) {
    const v1::Job job = submit_ok(spec);
    const auto before = test::wait_for_job(
        *stub_, job.job_id(), [](const v1::Job& j) { return j.tiles_done() >= 4 || done(j); }, 60s);
    if (!before) return std::nullopt;
    victim.process().send_signal(signal);
    EXPECT_FALSE(done(*before)) << "the job finished before the worker got signal " << signal;
    return test::wait_for_job(*stub_, job.job_id(), done, 90s);
  }

  // Waits until `tiles` tiles of the job are done, then kills the scheduler (SIGKILL) and waits
  // for it to go; the job as it was just before, nullopt when it got nowhere within a minute (or
  // the scheduler did not go).
  std::optional<v1::Job> kill_scheduler_after_tiles(test::SchedulerProcess& scheduler, const std::string& id,
                                                    std::uint32_t tiles) {
    const auto before = test::wait_for_job(
        *stub_, id, [tiles](const v1::Job& j) { return j.tiles_done() >= tiles || done(j); }, 60s);
    scheduler.process().send_signal(SIGKILL);
    if (!scheduler.process().wait_exit(10s)) {
      ADD_FAILURE() << "the scheduler outlived SIGKILL";
      return std::nullopt;
    }
    return before;
  }

  TileBuffer fetch_exr(const std::string& id) {
    const fs::path file = dir_ / (id + ".exr");
    const grpc::Status status = test::fetch_result(*stub_, id, v1::RESULT_KIND_EXR, file);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return status.ok() ? read_exr(file) : TileBuffer();
  }

  // Every engine's job submitted, watched and fetched, bit-identical to `farm render`.
  void expect_every_engine_identical_to_farm_render();
  // The scheduler killed -9 mid-job and started again on the same store: the job resumes, no
  // finished tile is rendered again, the image is bit-identical.
  void expect_restart_resumes_without_rendering_again();

  test::TempDir dir_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
  std::string store_;  // --store for every scheduler the test starts; empty: SQLite in the data dir
};

// The same on a PostgreSQL store (issue #18): `--store postgresql://...`, a database of its own.
class FarmSchedulerOnPostgresTest : public FarmSchedulerTest {
 protected:
  void SetUp() override {
    ASSERT_TRUE(where_.problem().empty()) << where_.problem();
    store_ = where_.location();
  }
  // Two static workers (their caches hold the Cornell box) for every scheduler of the farm: the
  // arguments that give them to one, float EXRs included.
  std::vector<std::string> start_shared_workers() {
    std::vector<std::string> args;
    for (const char* name : {"w1", "w2"}) {
      shared_workers_.push_back(start_worker(name));
      args.insert(args.end(), {"--worker", shared_workers_.back()->address()});
    }
    args.push_back("--float");
    return args;
  }
  test::StoreLocation where_{SqlDialect::PostgreSQL};
  std::vector<std::unique_ptr<test::WorkerProcess>> shared_workers_;
};

TEST_F(FarmSchedulerTest, SubmitWatchFetchIsBitIdenticalToFarmRenderForEveryEngine) {
  expect_every_engine_identical_to_farm_render();
}

TEST_F(FarmSchedulerOnPostgresTest, SubmitWatchFetchIsBitIdenticalToFarmRenderForEveryEngine) {
  expect_every_engine_identical_to_farm_render();
}

void FarmSchedulerTest::expect_every_engine_identical_to_farm_render() {
  auto worker = start_worker("w1", 2);
  auto scheduler = start_scheduler({"--worker", worker->address()});
  ASSERT_TRUE(stub_);
  for (const std::string engine : {"raster", "whitted", "path"}) {
    const v1::JobSpec spec = cornell(engine, 64, 48, engine == "path" ? 4 : 1, 16);
    const v1::Job submitted = submit_ok(spec);
    ASSERT_FALSE(submitted.job_id().empty());
    EXPECT_EQ(submitted.tiles_total(), 12u);
    EXPECT_EQ(submitted.engine(), engine);

    grpc::Status watch_status;
    const auto events = test::watch_job(*stub_, submitted.job_id(), 60s, &watch_status);
    ASSERT_TRUE(watch_status.ok()) << watch_status.error_message();
    ASSERT_FALSE(events.empty());
    EXPECT_TRUE(events.front().has_snapshot());
    EXPECT_TRUE(events.back().has_state_changed());
    const v1::Job& final_job = events.back().job();
    ASSERT_EQ(final_job.state(), v1::JOB_STATE_SUCCEEDED)
        << final_job.failure_reason() << scheduler->process().output();
    EXPECT_EQ(final_job.tiles_done(), 12u);
    EXPECT_EQ(final_job.tiles_rendered(), 12u);
    EXPECT_GT(final_job.render_seconds(), 0.0);
    if (engine == "path") {
      EXPECT_EQ(final_job.stats().samples(), 64u * 48u * 4u);
    }

    // `farm render` of the same job file, EXR in the same (default, half) format.
    const fs::path job_dir = dir_ / ("job-" + engine);
    fs::create_directories(job_dir / "assets");
    for (const auto& [path, file] : test::cornell_assets()) fs::copy_file(file, job_dir / path);
    std::ofstream(job_dir / "cornell.json") << spec.job_json();
    const fs::path local = dir_ / (engine + "-local.exr");
    const test::CommandResult r = test::run_command(test::farm_command(
        "render " + test::shell_quote((job_dir / "cornell.json").string()) + " --quiet --out " +
        test::shell_quote(local.string()) + " --preview none"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(differing_pixels(fetch_exr(submitted.job_id()), read_exr(local)), 0) << engine;

    const fs::path png = dir_ / (engine + ".png");
    EXPECT_TRUE(test::fetch_result(*stub_, submitted.job_id(), v1::RESULT_KIND_PREVIEW, png).ok());
    EXPECT_GT(fs::file_size(png), 0u);
  }
}

TEST_F(FarmSchedulerTest, KillingOneOfTwoWorkersMidJobStillFinishesWithIdenticalOutput) {
  // Workers that register themselves and fetch the assets from the scheduler.
  auto scheduler = start_scheduler({"--float", "--heartbeat-interval", "0.2"});
  ASSERT_TRUE(stub_);
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  auto w1 = start_worker("w1", 1, scheduler->address());
  auto w2 = start_worker("w2", 1, scheduler->address());
  const v1::JobSpec spec = cornell("path", 64, 48, 256, 8);  // 48 tiles, ~1 s on one thread
  const auto final_job = signal_worker_mid_job(spec, *w1, SIGKILL);
  ASSERT_TRUE(final_job);
  ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();
  // At most the killed worker's tiles in flight: two calls, each at most one row of 8 tiles.
  EXPECT_LE(final_job->tile_failures(), 16u);
  EXPECT_EQ(differing_pixels(fetch_exr(final_job->job_id()), render_locally(spec)), 0);
}

// A worker that stops answering (SIGSTOP: its socket still accepts connections) holds tiles until
// their deadline; they go to the other worker, and the hung one gets no more tiles, since it
// fails the health check it is probed with.
TEST_F(FarmSchedulerTest, AHungWorkersTilesMissTheirDeadlineAndFinishOnTheOther) {
  // Long enough for a healthy worker's 1024-spp tile (about 0.1 s) even on a machine busy with
  // other tests, such as the chaos soak: an unoptimised (debug) build needs more.
#ifdef NDEBUG
  const std::string deadline_s = "4", deadline_ms = "4000";
#else
  const std::string deadline_s = "8", deadline_ms = "8000";
#endif
  auto w1 = start_worker("w1");
  auto w2 = start_worker("w2");
  auto scheduler = start_scheduler(
      {"--worker", w1->address(), "--worker", w2->address(), "--tile-deadline", deadline_s, "--float"});
  ASSERT_TRUE(stub_);
  const v1::JobSpec spec = cornell("path", 64, 48, 1024, 8);  // 48 tiles, ~2 s on two threads
  const auto final_job = signal_worker_mid_job(spec, *w1, SIGSTOP);
  w1->process().send_signal(SIGCONT);
  ASSERT_TRUE(final_job);
  ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();
  EXPECT_GE(final_job->tile_failures(), 1u);
  EXPECT_TRUE(scheduler->process().wait_for_line("no result within the tile deadline of " + deadline_ms + " ms", 5s))
      << scheduler->process().output();
  EXPECT_EQ(differing_pixels(fetch_exr(final_job->job_id()), render_locally(spec)), 0);
}

// A registered worker that stops heartbeating is dropped long before any tile deadline, its
// tiles go to the other worker; when it comes back it registers again.
TEST_F(FarmSchedulerTest, AWorkerThatStopsHeartbeatingIsDroppedAndRegistersAgainLater) {
  auto scheduler = start_scheduler({"--float", "--heartbeat-interval", "0.2"});  // deadline 600 s
  ASSERT_TRUE(stub_);
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  auto w1 = start_worker("w1", 1, scheduler->address());
  auto w2 = start_worker("w2", 1, scheduler->address());
  const v1::JobSpec spec = cornell("path", 64, 48, 1024, 8);
  const auto final_job = signal_worker_mid_job(spec, *w1, SIGSTOP);
  ASSERT_TRUE(final_job);
  ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();
  EXPECT_GE(final_job->tile_failures(), 1u);  // the stopped worker's calls in flight
  EXPECT_TRUE(scheduler->process().wait_for_line("removed: no heartbeat for 600 ms", 5s))
      << scheduler->process().output();
  EXPECT_EQ(differing_pixels(fetch_exr(final_job->job_id()), render_locally(spec)), 0);

  w1->process().send_signal(SIGCONT);
  EXPECT_TRUE(scheduler->process().wait_for_line("worker w3-", 20s)) << scheduler->process().output();
}

// Priority beats submission order, tile by tile: an urgent job submitted last overtakes the one
// running and the one queued. ListJobs pages through them newest first.
TEST_F(FarmSchedulerTest, AnUrgentJobOvertakesAndListJobsPagesNewestFirst) {
  auto worker = start_worker("w1");
  auto scheduler = start_scheduler({"--worker", worker->address(), "--tiles-per-worker", "1"});
  ASSERT_TRUE(stub_);
  const v1::Job first = submit_ok(cornell("path", 64, 48, 256, 8));
  ASSERT_TRUE(test::wait_for_job(*stub_, first.job_id(),
                                 [](const v1::Job& j) { return j.tiles_done() >= 1 || done(j); }, 30s));
  const v1::Job second = submit_ok(cornell("path", 32, 32, 16, 16));
  v1::Job urgent;
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  ASSERT_TRUE(test::submit(*stub_, cornell("path", 32, 32, 16, 16), urgent, 5).ok());
  EXPECT_EQ(urgent.priority(), 5);
  std::map<std::string, v1::Job> final_jobs;
  for (const v1::Job& j : {first, second, urgent}) {
    const auto f = test::wait_for_job(*stub_, j.job_id(), done, 60s);
    ASSERT_TRUE(f);
    ASSERT_EQ(f->state(), v1::JOB_STATE_SUCCEEDED) << f->failure_reason();
    final_jobs[j.job_id()] = *f;
  }
  const auto finished_ms = [&](const v1::Job& j) {
    const auto& t = final_jobs[j.job_id()].finished_at();
    return t.seconds() * 1000 + t.nanos() / 1000000;
  };
  EXPECT_LT(finished_ms(urgent), finished_ms(first)) << "the urgent job did not overtake the running one";
  EXPECT_LT(finished_ms(first), finished_ms(second));  // same priority: submission order

  std::vector<std::string> listed;
  std::string token;
  int pages = 0;
  do {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 10s);
    v1::ListJobsRequest request;
    request.set_page_size(2);
    request.set_page_token(token);
    request.add_states(v1::JOB_STATE_SUCCEEDED);
    v1::ListJobsResponse response;
    ASSERT_TRUE(stub_->ListJobs(&context, request, &response).ok());
    for (const v1::Job& j : response.jobs()) listed.push_back(j.job_id());
    token = response.next_page_token();
    ++pages;
  } while (!token.empty() && pages < 5);
  EXPECT_EQ(pages, 2);
  EXPECT_EQ(listed, (std::vector<std::string>{urgent.job_id(), second.job_id(), first.job_id()}));
}

// `farm scheduler --worker ADDR` with a worker started without --scheduler and an empty cache:
// the worker cannot fetch, so the scheduler sends the job's files with the call.
TEST_F(FarmSchedulerTest, AStaticWorkerWithAnEmptyCacheGetsTheJobsFilesInline) {
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", (dir_ / "empty").string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  auto scheduler = start_scheduler({"--worker", worker.address(), "--float"});
  ASSERT_TRUE(stub_);
  const v1::JobSpec spec = cornell("whitted", 48, 32, 1, 16);
  const v1::Job job = submit_ok(spec);
  const auto final_job = test::wait_for_job(*stub_, job.job_id(), done, 60s);
  ASSERT_TRUE(final_job);
  ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();
  EXPECT_EQ(final_job->tile_failures(), 0u);
  EXPECT_EQ(differing_pixels(fetch_exr(final_job->job_id()), render_locally(spec)), 0);
  const AssetStore kept(dir_ / "empty" / "blobs");
  for (const v1::AssetRef& ref : spec.assets()) EXPECT_TRUE(kept.has(ref.sha256())) << ref.path();
}

TEST_F(FarmSchedulerTest, RestartedSchedulerResumesWithoutRenderingFinishedTilesAgain) {
  expect_restart_resumes_without_rendering_again();
}

TEST_F(FarmSchedulerOnPostgresTest, RestartedSchedulerResumesWithoutRenderingFinishedTilesAgain) {
  expect_restart_resumes_without_rendering_again();
}

// The store's server stops mid-job and comes back a few seconds later: the scheduler says so both
// times, keeps its registered worker, counts no failure, renders no tile twice (a result that
// came back meanwhile waits on disk for its mark) and finishes the job bit-identical.
TEST_F(FarmSchedulerOnPostgresTest, AStoreThatGoesAwayMidJobAndComesBackLosesNothing) {
  auto scheduler = start_scheduler({"--float", "--heartbeat-interval", "0.2"});
  ASSERT_TRUE(stub_);
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  auto worker = start_worker("w1", 1, scheduler->address());
  const v1::JobSpec spec = cornell("path", 64, 48, 512, 8);
  const v1::Job job = submit_ok(spec);
  const auto before = test::wait_for_job(
      *stub_, job.job_id(), [](const v1::Job& j) { return j.tiles_done() >= 6 || done(j); }, 60s);
  ASSERT_TRUE(before);
  ASSERT_FALSE(done(*before)) << "the job finished before the store went away";

  ASSERT_TRUE(where_.server()->stop()) << where_.server()->problem();
  EXPECT_TRUE(scheduler->process().wait_for_line("no unit is claimed or marked until it answers", 30s))
      << scheduler->process().output();
  // Away for longer than a silent worker is kept (3 heartbeats of 0.2 s): it must still be there.
  std::this_thread::sleep_for(3s);
  ASSERT_TRUE(where_.server()->start()) << where_.server()->problem();
  EXPECT_TRUE(scheduler->process().wait_for_line("job store answers again", 30s)) << scheduler->process().output();

  const auto final_job = test::wait_for_job(*stub_, job.job_id(), done, 90s);
  ASSERT_TRUE(final_job);
  ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason() << scheduler->process().output();
  EXPECT_EQ(final_job->tile_failures(), 0u);
  EXPECT_EQ(final_job->tiles_rendered(), final_job->tiles_total());
  EXPECT_EQ(differing_pixels(fetch_exr(final_job->job_id()), render_locally(spec)), 0);
  EXPECT_EQ(scheduler->process().output().find("removed"), std::string::npos) << scheduler->process().output();
}

// Two schedulers on one PostgreSQL store and one (shared) data dir, both sending units to the same
// two workers. The one the job was submitted to is killed -9 mid-job: the other carries it on,
// renders the dead one's running units once its lease ran out (2 s here), renders no finished unit
// again, and ends it bit-identical; the job and its image are served by the survivor.
TEST_F(FarmSchedulerOnPostgresTest, KillingOneOfTwoSchedulersMidJobLeavesTheOtherToFinishIt) {
  const std::vector<std::string> workers = start_shared_workers();
  auto a = start_scheduler(workers);
  ASSERT_TRUE(stub_);
  const v1::JobSpec spec = cornell("path", 64, 48, 512, 8);
  const v1::Job job = submit_ok(spec);
  auto b = start_scheduler(workers);  // stub_ talks to b from here on
  ASSERT_TRUE(stub_);
  const auto before = test::wait_for_job(
      *stub_, job.job_id(), [](const v1::Job& j) { return j.tiles_done() >= 6 || done(j); }, 60s);
  ASSERT_TRUE(before);
  ASSERT_FALSE(done(*before)) << "the job finished before the kill";
  a->process().send_signal(SIGKILL);
  ASSERT_TRUE(a->process().wait_exit(10s));
  EXPECT_TRUE(b->process().wait_for_line("its lease ran out", 30s)) << b->process().output();

  const auto final_job = test::wait_for_job(*stub_, job.job_id(), done, 90s);
  ASSERT_TRUE(final_job);
  ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason() << b->process().output();
  EXPECT_EQ(final_job->tile_failures(), 0u);
  EXPECT_EQ(final_job->tiles_rendered(), final_job->tiles_total());  // none rendered twice
  EXPECT_EQ(differing_pixels(fetch_exr(final_job->job_id()), render_locally(spec)), 0);
}

// A scheduler killed -9 in the middle of a dependency release (FARM_FAILPOINT stops it after its
// changes, before their commit; server/common/failpoint.h) leaves the waiting job waiting: the
// next scheduler on the store releases it, once, and renders it (issue #36).
TEST_F(FarmSchedulerOnPostgresTest, ASchedulerKilledDuringADependencyReleaseLeavesItToTheNextOnce) {
  const std::vector<std::string> workers = start_shared_workers();
  ::setenv("FARM_FAILPOINT", "dependency-release", 1);
  auto a = start_scheduler(workers);
  ::unsetenv("FARM_FAILPOINT");
  ASSERT_TRUE(stub_);
  const v1::JobSpec spec = cornell("raster", 48, 32, 1, 16);
  const v1::Job first = submit_ok(spec);
  // Held while the second is queued after it, so that a's release comes after both answers.
  {
    grpc::ClientContext context;
    v1::PauseJobRequest pause;
    pause.set_job_id(first.job_id());
    pause.set_paused(true);
    v1::PauseJobResponse paused;
    ASSERT_TRUE(stub_->PauseJob(&context, pause, &paused).ok());
  }
  v1::SubmitJobRequest request;
  *request.mutable_job() = spec;
  request.add_after(first.job_id());
  v1::SubmitJobResponse second;
  {
    grpc::ClientContext context;
    ASSERT_TRUE(stub_->SubmitJob(&context, request, &second).ok());
  }
  ASSERT_EQ(second.job().state(), v1::JOB_STATE_WAITING);
  {
    grpc::ClientContext context;
    v1::PauseJobRequest resume;
    resume.set_job_id(first.job_id());
    v1::PauseJobResponse resumed;
    static_cast<void>(stub_->PauseJob(&context, resume, &resumed));  // its answer may be cut off by the kill
  }
  ASSERT_TRUE(a->process().wait_exit(60s)) << "the scheduler never reached its failpoint:\n" << a->process().output();
  EXPECT_EQ(a->process().output().find("the jobs it waits for have ended"), std::string::npos) << a->process().output();

  auto b = start_scheduler(workers);  // stub_ talks to b from here on
  ASSERT_TRUE(stub_);
  const auto done_job = test::wait_for_job(*stub_, second.job().job_id(), done, 90s);
  ASSERT_TRUE(done_job);
  ASSERT_EQ(done_job->state(), v1::JOB_STATE_SUCCEEDED) << done_job->failure_reason() << b->process().output();
  EXPECT_EQ(test::get_job(*stub_, first.job_id())->state(), v1::JOB_STATE_SUCCEEDED);
  // Released once (one waiting -> queued in its log), started once.
  grpc::ClientContext context;
  v1::GetJobLogRequest log_request;
  log_request.set_job_id(second.job().job_id());
  v1::GetJobLogResponse log;
  ASSERT_TRUE(stub_->GetJobLog(&context, log_request, &log).ok());
  int released = 0, started = 0;
  for (const v1::JobLogEntry& e : log.entries()) {
    if (!e.event().has_state_changed()) continue;
    const v1::JobStateChanged& c = e.event().state_changed();
    released += c.from() == v1::JOB_STATE_WAITING && c.to() == v1::JOB_STATE_QUEUED;
    started += c.to() == v1::JOB_STATE_RUNNING;
  }
  EXPECT_EQ(released, 1);
  EXPECT_EQ(started, 1);
  EXPECT_EQ(done_job->tiles_rendered(), done_job->tiles_total());
}

// Two schedulers on one PostgreSQL store and data dir, both sending units to the same two workers,
// take 50 jobs at once, half through each: none is lost, no unit is rendered twice (each frame
// merged and each job ended by one of them), and every image is bit-identical to the job rendered
// here, whichever scheduler it is fetched from.
TEST_F(FarmSchedulerOnPostgresTest, TwoSchedulersTakeFiftyJobsAtOnceAndRenderEachOnce) {
  const std::vector<std::string> workers = start_shared_workers();
  auto a = start_scheduler(workers);
  ASSERT_TRUE(stub_);
  std::unique_ptr<v1::Scheduler::Stub> to_a = std::move(stub_);
  auto b = start_scheduler(workers);
  ASSERT_TRUE(stub_);
  std::unique_ptr<v1::Scheduler::Stub> to_b = std::move(stub_);
  ASSERT_TRUE(test::upload_assets(*to_a, test::cornell_assets()).ok());
  const std::vector<v1::JobSpec> specs{cornell("raster", 48, 32, 1, 16), cornell("whitted", 48, 32, 1, 16),
                                       cornell("path", 48, 32, 4, 16)};
  constexpr int kJobs = 50;
  std::vector<std::string> ids(kJobs);
  const auto submit_half = [&](v1::Scheduler::Stub& stub, int parity) {
    for (int i = parity; i < kJobs; i += 2) {
      v1::Job job;
      const grpc::Status status = test::submit(stub, specs[static_cast<std::size_t>(i) % specs.size()], job);
      EXPECT_TRUE(status.ok()) << status.error_message();
      ids[static_cast<std::size_t>(i)] = job.job_id();
    }
  };
  std::thread through_a(submit_half, std::ref(*to_a), 0);
  std::thread through_b(submit_half, std::ref(*to_b), 1);
  through_a.join();
  through_b.join();

  std::vector<TileBuffer> expected;
  for (const v1::JobSpec& spec : specs) expected.push_back(render_locally(spec));
  for (int i = 0; i < kJobs; ++i) {
    v1::Scheduler::Stub& stub = i % 3 == 0 ? *to_a : *to_b;  // not always where it was submitted
    const auto final_job = test::wait_for_job(stub, ids[static_cast<std::size_t>(i)], done, 120s);
    ASSERT_TRUE(final_job) << "job " << i;
    ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << i << ": " << final_job->failure_reason();
    EXPECT_EQ(final_job->tile_failures(), 0u) << i;
    EXPECT_EQ(final_job->tiles_rendered(), final_job->tiles_total()) << i;
    const fs::path file = dir_ / fmt::format("job{}.exr", i);
    ASSERT_TRUE(test::fetch_result(stub, final_job->job_id(), v1::RESULT_KIND_EXR, file).ok()) << i;
    EXPECT_EQ(differing_pixels(read_exr(file), expected[static_cast<std::size_t>(i) % specs.size()]), 0) << i;
  }
  // Each job ended once: by one scheduler or the other, never both.
  const std::string logs = a->process().output() + b->process().output();
  std::size_t ended = 0;
  for (std::size_t at = logs.find(" done: "); at != std::string::npos; at = logs.find(" done: ", at + 1)) ++ended;
  EXPECT_EQ(ended, static_cast<std::size_t>(kJobs)) << logs;
}

// A job watched on a scheduler that renders none of it (it has no workers): the other one's units,
// frame and end reach the watch through the store (LISTEN/NOTIFY), every unit done after the
// snapshot announced once, and the job is served by either.
TEST_F(FarmSchedulerOnPostgresTest, AWatchOnOneSchedulerSeesTheWorkOfTheOther) {
  const std::vector<std::string> workers = start_shared_workers();
  auto renders = start_scheduler(workers);
  ASSERT_TRUE(stub_);
  auto watched = start_scheduler({"--float"});  // stub_ talks to it from here on
  ASSERT_TRUE(stub_);
  const v1::JobSpec spec = cornell("path", 64, 48, 256, 8);
  const v1::Job job = submit_ok(spec);
  grpc::Status status;
  const std::vector<v1::JobEvent> events = test::watch_job(*stub_, job.job_id(), 120s, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_FALSE(events.empty());
  ASSERT_TRUE(events.front().has_snapshot());
  const v1::Job& snapshot = events.front().job();
  ASSERT_FALSE(done(snapshot)) << "the job ended before the watch began";
  std::uint32_t announced = 0;
  bool frame_finished = false;
  for (const v1::JobEvent& e : events) {
    if (e.has_tile_finished()) {
      announced += e.tile_finished().tile_count();
      EXPECT_FALSE(e.tile_finished().worker().empty());
    }
    frame_finished |= e.has_frame_finished();
    EXPECT_FALSE(e.has_tile_failed()) << e.tile_failed().reason();
  }
  EXPECT_EQ(announced, snapshot.tiles_total() - snapshot.tiles_done());
  EXPECT_TRUE(frame_finished);
  ASSERT_TRUE(events.back().has_state_changed());
  EXPECT_EQ(events.back().state_changed().to(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_EQ(events.back().job().tiles_done(), events.back().job().tiles_total());
  EXPECT_EQ(differing_pixels(fetch_exr(job.job_id()), render_locally(spec)), 0);
  EXPECT_EQ(watched->process().output().find(" done: "), std::string::npos) << "ended by the watched one";
}

// A job cancelled on one scheduler while the other renders it: the other's calls in flight stop
// (told through the store), the job stays cancelled with its units as they were, and the workers
// go straight on to the next job.
TEST_F(FarmSchedulerOnPostgresTest, ACancelOnOneSchedulerStopsTheUnitsOfTheOther) {
  const std::vector<std::string> workers = start_shared_workers();
  auto renders = start_scheduler(workers);
  ASSERT_TRUE(stub_);
  const v1::Job big = submit_ok(cornell("path", 256, 256, 256, 64));  // many seconds of work
  ASSERT_TRUE(test::wait_for_job(*stub_, big.job_id(),
                                 [](const v1::Job& j) { return j.state() == v1::JOB_STATE_RUNNING; }, 30s));
  auto cancels = start_scheduler({});  // stub_ talks to it from here on
  ASSERT_TRUE(stub_);
  const v1::Job at_cancel = cancel_ok(big.job_id());
  ASSERT_EQ(at_cancel.state(), v1::JOB_STATE_CANCELLED);
  EXPECT_TRUE(renders->process().wait_for_line("JOB_STATE_CANCELLED on another scheduler: its units in flight here stopped", 30s))
      << renders->process().output();

  const v1::Job small = submit_ok(cornell("raster", 32, 32, 1, 16));
  const auto small_done = test::wait_for_job(*stub_, small.job_id(), done, 60s);
  ASSERT_TRUE(small_done);
  EXPECT_EQ(small_done->state(), v1::JOB_STATE_SUCCEEDED) << small_done->failure_reason();
  const auto cancelled = test::get_job(*stub_, big.job_id());
  ASSERT_TRUE(cancelled);
  EXPECT_EQ(cancelled->state(), v1::JOB_STATE_CANCELLED);
  EXPECT_EQ(cancelled->tiles_done(), at_cancel.tiles_done());
}

// One worker given both schedulers of a farm (`farm worker --scheduler A,B`): it registers with
// each, learns who each is, fetches a call's files from the scheduler that sent it, renders the
// jobs of both bit-identical, and goes on serving the survivor when the other is killed.
TEST_F(FarmSchedulerOnPostgresTest, AWorkerOfTwoSchedulersServesBothAndOutlivesEither) {
  auto a = start_scheduler({"--float"});
  ASSERT_TRUE(stub_);
  std::unique_ptr<v1::Scheduler::Stub> to_a = std::move(stub_);
  auto b = start_scheduler({"--float"});
  ASSERT_TRUE(stub_);
  auto worker = start_worker("w", 2, a->address() + "," + b->address());
  for (const auto* s : {a.get(), b.get()}) {
    EXPECT_TRUE(worker->process().wait_for_line("registered with the scheduler " + s->address() + " (", 20s))
        << worker->process().output();
  }
  const v1::JobSpec raster = cornell("raster", 48, 32, 1, 16), path = cornell("path", 48, 32, 4, 16);
  ASSERT_TRUE(test::upload_assets(*to_a, test::cornell_assets()).ok());
  v1::Job on_a, on_b;
  ASSERT_TRUE(test::submit(*to_a, raster, on_a).ok());
  ASSERT_TRUE(test::submit(*stub_, path, on_b).ok());
  for (const auto& [stub, job, spec] : {std::tuple{to_a.get(), on_a, raster}, std::tuple{stub_.get(), on_b, path}}) {
    const auto final_job = test::wait_for_job(*stub, job.job_id(), done, 60s);
    ASSERT_TRUE(final_job);
    ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason() << worker->process().output();
    const fs::path file = dir_ / (job.job_id() + ".exr");
    ASSERT_TRUE(test::fetch_result(*stub, job.job_id(), v1::RESULT_KIND_EXR, file).ok());
    EXPECT_EQ(differing_pixels(read_exr(file), render_locally(spec)), 0);
  }
  // The files came from a scheduler of the two, once.
  const std::string output = worker->process().output();
  EXPECT_NE(output.find("files fetched from 127.0.0.1:"), std::string::npos) << output;

  a->process().send_signal(SIGKILL);
  ASSERT_TRUE(a->process().wait_exit(10s));
  const v1::Job later = submit_ok(cornell("whitted", 48, 32, 1, 16));
  const auto final_job = test::wait_for_job(*stub_, later.job_id(), done, 60s);
  ASSERT_TRUE(final_job);
  EXPECT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason() << worker->process().output();
}

// --store takes only a PostgreSQL URL (exit 2 naming the flag); a server that is not there stops
// the scheduler at start with its address and no password (exit 1), before it listens.
TEST_F(FarmSchedulerTest, ABadOrUnreachableStoreIsAnErrorNamingIt) {
  const std::string data = test::shell_quote((dir_ / "data").string());
  const test::CommandResult bad = test::run_command(test::farm_command("scheduler --data-dir " + data + " --store jobs.db"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--store 'jobs.db'"), std::string::npos) << bad.output;
  const test::CommandResult away = test::run_command(test::farm_command(
      "scheduler --listen 127.0.0.1:0 --data-dir " + data + " --store postgresql://farm:secret@127.0.0.1:1/farm"));
  EXPECT_EQ(away.exit_code, 1) << away.output;
  EXPECT_NE(away.output.find("cannot reach job store postgresql://...@127.0.0.1:1/farm"), std::string::npos)
      << away.output;
  EXPECT_EQ(away.output.find("secret"), std::string::npos) << away.output;
  EXPECT_EQ(away.output.find("listening"), std::string::npos) << away.output;
}

void FarmSchedulerTest::expect_restart_resumes_without_rendering_again() {
  auto worker = start_worker("w1");
  auto scheduler = start_scheduler({"--worker", worker->address(), "--float"});
  ASSERT_TRUE(stub_);
  const v1::JobSpec spec = cornell("path", 64, 48, 512, 8);
  const v1::Job job = submit_ok(spec);
  const auto before = kill_scheduler_after_tiles(*scheduler, job.job_id(), 6);
  ASSERT_TRUE(before);
  ASSERT_NE(before->state(), v1::JOB_STATE_SUCCEEDED) << "the job finished before the kill";

  scheduler = start_scheduler({"--worker", worker->address(), "--float"});
  ASSERT_TRUE(stub_);
  const auto resumed = test::get_job(*stub_, job.job_id());
  ASSERT_TRUE(resumed);
  EXPECT_GE(resumed->tiles_done(), before->tiles_done());
  const auto final_job = test::wait_for_job(*stub_, job.job_id(), done, 90s);
  ASSERT_TRUE(final_job);
  ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();
  // Every tile result was accepted exactly once across both schedulers: none rendered again.
  EXPECT_EQ(final_job->tiles_rendered(), final_job->tiles_total());
  EXPECT_EQ(final_job->tile_failures(), 0u);
  EXPECT_EQ(differing_pixels(fetch_exr(final_job->job_id()), render_locally(spec)), 0);
}

// How a tile result file is damaged while the scheduler is down.
enum class Damage { Truncate, Delete, FlipBytes };

void damage(const fs::path& file, Damage how) {
  switch (how) {
    case Damage::Truncate:
      fs::resize_file(file, fs::file_size(file) / 2);
      return;
    case Damage::Delete:
      fs::remove(file);
      return;
    case Damage::FlipBytes: {
      std::string bytes = test::read_file(file);
      ASSERT_GT(bytes.size(), 64u);
      for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 16; ++i) bytes[i] = static_cast<char>(~bytes[i]);
      std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
      return;
    }
  }
}

class DamagedTileResultsTest : public FarmSchedulerTest, public ::testing::WithParamInterface<Damage> {};

// The scheduler is killed mid-job and every tile result file of the job damaged before it comes
// back: the done tiles whose files are damaged are rendered again (the log names each file), never
// merged, and the job succeeds with the frame `farm render` gives.
TEST_P(DamagedTileResultsTest, DamagedTileFilesAreRenderedAgainAndTheFrameIsBitIdentical) {
  auto worker = start_worker("w1");
  auto scheduler = start_scheduler({"--worker", worker->address(), "--float"});
  ASSERT_TRUE(stub_);
  const v1::JobSpec spec = cornell("path", 64, 48, 1024, 8);
  const v1::Job job = submit_ok(spec);
  const auto before = kill_scheduler_after_tiles(*scheduler, job.job_id(), 2);
  ASSERT_TRUE(before);
  ASSERT_NE(before->state(), v1::JOB_STATE_SUCCEEDED) << "the job finished before the kill";

  std::vector<std::string> damaged;
  for (const fs::directory_entry& e : fs::directory_iterator(dir_ / "data" / "tiles" / job.job_id())) {
    if (e.path().filename().string().starts_with(".")) continue;
    damaged.push_back(e.path().string());
    damage(e.path(), GetParam());
  }
  ASSERT_FALSE(damaged.empty());

  scheduler = start_scheduler({"--worker", worker->address(), "--float"});
  ASSERT_TRUE(stub_);
  const auto final_job = test::wait_for_job(*stub_, job.job_id(), done, 90s);
  ASSERT_TRUE(final_job);
  ASSERT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();
  EXPECT_EQ(final_job->tiles_done(), final_job->tiles_total());
  // At least the tiles done before the kill were accepted twice.
  EXPECT_GE(final_job->tiles_rendered(), final_job->tiles_total() + before->tiles_done());
  EXPECT_EQ(final_job->tile_failures(), 0u);
  EXPECT_EQ(differing_pixels(fetch_exr(final_job->job_id()), render_locally(spec)), 0);
  const std::string log = scheduler->process().output();
  int named = 0;
  for (const std::string& file : damaged) named += log.find(file) != std::string::npos ? 1 : 0;
  EXPECT_GE(named, 1) << log;
  EXPECT_NE(log.find("rendered again, not merged"), std::string::npos) << log;
}

INSTANTIATE_TEST_SUITE_P(EachDamage, DamagedTileResultsTest,
                         ::testing::Values(Damage::Truncate, Damage::Delete, Damage::FlipBytes),
                         [](const ::testing::TestParamInfo<Damage>& p) {
                           switch (p.param) {
                             case Damage::Truncate: return std::string("Truncated");
                             case Damage::Delete: return std::string("Deleted");
                             case Damage::FlipBytes: return std::string("BytesFlipped");
                           }
                           return std::string();
                         });

TEST_F(FarmSchedulerTest, CancelStopsTheJobQuicklyAndTheWorkerServesTheNextJob) {
  auto worker = start_worker("w1");
  auto scheduler = start_scheduler({"--worker", worker->address()});
  ASSERT_TRUE(stub_);
  const v1::Job big = submit_ok(cornell("path", 256, 256, 256, 64));  // many seconds of work
  ASSERT_TRUE(test::wait_for_job(*stub_, big.job_id(),
                                 [](const v1::Job& j) { return j.state() == v1::JOB_STATE_RUNNING; }, 30s));
  const auto start = std::chrono::steady_clock::now();
  const v1::Job at_cancel = cancel_ok(big.job_id());
  ASSERT_EQ(at_cancel.state(), v1::JOB_STATE_CANCELLED);
  const std::uint32_t done_at_cancel = at_cancel.tiles_done();

  // The worker is free again within a second or two: a small job goes straight through.
  const v1::Job small = submit_ok(cornell("raster", 32, 32, 1, 16));
  const auto small_done = test::wait_for_job(*stub_, small.job_id(), done, 20s);
  ASSERT_TRUE(small_done);
  EXPECT_EQ(small_done->state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_LT(std::chrono::steady_clock::now() - start, 5s);
  const auto cancelled = test::get_job(*stub_, big.job_id());
  EXPECT_EQ(cancelled->state(), v1::JOB_STATE_CANCELLED);
  EXPECT_EQ(cancelled->tiles_done(), done_at_cancel);

  v1::GetResultRequest get;
  get.set_job_id(big.job_id());
  grpc::ClientContext result_context;
  auto reader = stub_->GetResult(&result_context, get);
  v1::FileChunk chunk;
  while (reader->Read(&chunk)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::FAILED_PRECONDITION);
}

// A job of one tile that no worker finishes in a test's lifetime (2^20 samples a pixel, the most
// a job may ask for). The worker has one render thread: were the cancelled render still running,
// the next job's tile would wait behind it until the 600 s tile deadline.
TEST_F(FarmSchedulerTest, CancellingAHugeSppJobFreesTheWorkerForTheNextJob) {
  auto worker = start_worker("w1", 1);
  auto scheduler = start_scheduler({"--worker", worker->address()});
  ASSERT_TRUE(stub_);
  const v1::Job huge = submit_ok(cornell("path", 16, 16, kMaxSpp, 16));
  ASSERT_TRUE(test::wait_for_job(*stub_, huge.job_id(),
                                 [](const v1::Job& j) { return j.state() == v1::JOB_STATE_RUNNING; }, 30s));
  std::this_thread::sleep_for(500ms);  // into the render (an earlier cancel proves less, never fails)
  ASSERT_EQ(cancel_ok(huge.job_id()).state(), v1::JOB_STATE_CANCELLED);

  const v1::Job small = submit_ok(cornell("raster", 32, 32, 1, 16));
  const auto small_done = test::wait_for_job(*stub_, small.job_id(), done, 30s);
  ASSERT_TRUE(small_done) << "the worker is still rendering the cancelled job\n" << worker->process().output();
  EXPECT_EQ(small_done->state(), v1::JOB_STATE_SUCCEEDED) << small_done->failure_reason();
}

// SIGTERM while the only worker renders hours of tiles: the scheduler cancels its calls and exits
// 0; the worker stops rendering (a call to it comes back), and the restarted scheduler finds the
// tiles queued again, none of them done (nothing half-rendered was accepted).
TEST_F(FarmSchedulerTest, SigtermWhileAWorkerRendersHugeTilesQueuesThemAgainAndFreesTheWorker) {
  auto worker = start_worker("w1", 1);
  auto scheduler = start_scheduler({"--worker", worker->address()});
  ASSERT_TRUE(stub_);
  const v1::Job huge = submit_ok(cornell("path", 32, 32, kMaxSpp, 16));
  ASSERT_TRUE(test::wait_for_job(*stub_, huge.job_id(),
                                 [](const v1::Job& j) { return j.state() == v1::JOB_STATE_RUNNING; }, 30s));
  std::this_thread::sleep_for(500ms);
  scheduler->process().send_signal(SIGTERM);
  const std::optional<int> code = scheduler->process().wait_exit(15s);
  ASSERT_TRUE(code.has_value()) << "scheduler still running after SIGTERM\n" << scheduler->process().output();
  EXPECT_EQ(*code, 0) << scheduler->process().output();

  // The worker's one render thread is free: a small tile straight to it comes back.
  auto worker_stub = v1::Worker::NewStub(grpc::CreateChannel(worker->address(), grpc::InsecureChannelCredentials()));
  v1::RenderTileRequest tile;
  *tile.mutable_job() = cornell("raster", 16, 16, 1, 16);
  tile.mutable_rect()->set_x1(16);
  tile.mutable_rect()->set_y1(16);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 30s);
  v1::RenderTileResponse rendered;
  const grpc::Status status = worker_stub->RenderTile(&context, tile, &rendered);
  EXPECT_TRUE(status.ok()) << "the worker is still rendering the abandoned tiles: " << status.error_message();

  auto restarted = start_scheduler({});  // no workers: the job stays as the store kept it
  ASSERT_TRUE(stub_);
  const auto resumed = test::get_job(*stub_, huge.job_id());
  ASSERT_TRUE(resumed);
  EXPECT_FALSE(done(*resumed)) << v1::JobState_Name(resumed->state());
  EXPECT_EQ(resumed->tiles_done(), 0u);
}

// SIGTERM while a client watches a job: once the server shuts down it refuses the registered
// worker's heartbeats and asset fetches, and its grace period (1.4 s, held by the WatchJob
// stream) outlasts the worker's heartbeat limit (3 x 0.2 s). Neither may cost the job anything:
// the tiles in flight go back to the queue with no lost rendering counted, and the worker is not
// dropped. (The chaos soak once saw every worker dropped at its SIGTERM, their tiles counted
// lost; a worker still fetching the job's files failed its tiles.)
TEST_F(FarmSchedulerTest, SigtermWhileAClientWatchesDropsNoWorkerForTheRefusedHeartbeats) {
  auto scheduler = start_scheduler({"--heartbeat-interval", "0.2"});
  ASSERT_TRUE(stub_);
  auto worker = start_worker("w1", 1, scheduler->address());
  const v1::Job huge = submit_ok(cornell("path", 32, 32, kMaxSpp, 16));
  const test::RunningTiles running(dir_ / "data" / "jobs.db");
  const auto until = std::chrono::steady_clock::now() + 30s;
  while (running.on_worker(worker->address()).empty() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_FALSE(running.on_worker(worker->address()).empty()) << "no tile reached the worker";

  std::promise<void> subscribed;
  std::thread watcher([&] {
    test::watch_job(*stub_, huge.job_id(), 60s, nullptr, [&] { subscribed.set_value(); });
  });
  struct Join {
    std::thread& t;
    ~Join() { t.join(); }
  } join{watcher};
  ASSERT_EQ(subscribed.get_future().wait_for(30s), std::future_status::ready);
  scheduler->process().send_signal(SIGTERM);
  const std::optional<int> code = scheduler->process().wait_exit(15s);
  ASSERT_TRUE(code.has_value()) << "scheduler still running after SIGTERM\n" << scheduler->process().output();
  EXPECT_EQ(*code, 0) << scheduler->process().output();
  EXPECT_EQ(scheduler->process().output().find("removed: no heartbeat"), std::string::npos)
      << scheduler->process().output();

  auto restarted = start_scheduler({});  // no workers: the job stays as the store kept it
  ASSERT_TRUE(stub_);
  const auto resumed = test::get_job(*stub_, huge.job_id());
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed->tile_failures(), 0u) << "tiles counted lost at the scheduler's own shutdown:\n" << scheduler->process().output();
  EXPECT_EQ(resumed->tiles_done(), 0u);
  EXPECT_FALSE(done(*resumed)) << v1::JobState_Name(resumed->state());
}

// A model whose loading takes minutes in little memory: Assimp triangulates each polygon by ear
// clipping, quadratic in its vertices, and a face may have 32767 of them.
void write_slow_model(const fs::path& file) {
  constexpr int kVertices = 32000, kFaces = 24;
  std::ofstream out(file);
  for (int i = 0; i < kVertices; ++i) {
    const double a = 2.0 * std::numbers::pi * i / kVertices, r = i % 2 == 0 ? 1.0 : 0.6;  // a star: concave
    out << "v " << r * std::cos(a) << ' ' << r * std::sin(a) << " 0\n";
  }
  std::string face = "f";
  for (int i = 1; i <= kVertices; ++i) face += ' ' + std::to_string(i);
  for (int f = 0; f < kFaces; ++f) out << face << '\n';
}

// SubmitJob validates by loading the models, which cannot be interrupted: SIGTERM in the middle
// of loading a huge one used to wait for the load to finish. Now the call is abandoned after the
// grace period and the scheduler exits 0; the store holds no trace of the job, and the client
// was never told it was queued.
TEST_F(FarmSchedulerTest, SigtermWhileSubmitJobLoadsAHugeModelExitsWithoutQueueingIt) {
  auto scheduler = start_scheduler({});
  ASSERT_TRUE(stub_);
  const fs::path model = dir_ / "slow.obj";
  write_slow_model(model);
  const std::vector<std::pair<std::string, fs::path>> files{{"slow.obj", model}};
  ASSERT_TRUE(test::upload_assets(*stub_, files).ok());
  const v1::JobSpec spec = test::make_job_spec(
      R"({"version": 1, "name": "slow", "scene": {"objects": [{"file": "slow.obj"}]},
          "render": {"engine": "raster", "width": 16, "height": 16}})",
      files, "slow.json");

  grpc::Status submitted;
  std::thread submit([&] {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 600s);
    v1::SubmitJobRequest request;
    *request.mutable_job() = spec;
    v1::SubmitJobResponse response;
    submitted = stub_->SubmitJob(&context, request, &response);
  });
  std::this_thread::sleep_for(1s);  // into the load
  scheduler->process().send_signal(SIGTERM);
  const std::optional<int> code = scheduler->process().wait_exit(20s);
  submit.join();
  ASSERT_TRUE(code.has_value()) << "scheduler still running after SIGTERM\n" << scheduler->process().output();
  EXPECT_EQ(*code, 0) << scheduler->process().output();
  EXPECT_FALSE(submitted.ok()) << "the model loaded before SIGTERM: make it slower";

  auto restarted = start_scheduler({});
  ASSERT_TRUE(stub_);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 10s);
  v1::ListJobsResponse jobs;
  ASSERT_TRUE(stub_->ListJobs(&context, v1::ListJobsRequest(), &jobs).ok());
  EXPECT_EQ(jobs.jobs_size(), 0);
}

TEST_F(FarmSchedulerTest, BadJobsAreRejectedAtSubmitAndTheFarmKeepsServing) {
  auto worker = start_worker("w1");
  auto scheduler = start_scheduler({"--worker", worker->address()});
  ASSERT_TRUE(stub_);
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  const auto expect_rejected = [&](const v1::JobSpec& spec, grpc::StatusCode code,
                                   const std::string& needle) {
    v1::Job job;
    const grpc::Status status = test::submit(*stub_, spec, job);
    EXPECT_EQ(status.error_code(), code) << status.error_message();
    EXPECT_NE(status.error_message().find(needle), std::string::npos) << status.error_message();
  };

  v1::JobSpec malformed = cornell("raster", 32, 32, 1, 16);
  malformed.set_job_json("{ \"version\": 1, \"scene\": ");
  expect_rejected(malformed, grpc::StatusCode::INVALID_ARGUMENT, "cornell.json");

  nlohmann::json missing_model = nlohmann::json::parse(test::cornell_job_json("raster", 32, 32, 1));
  missing_model["scene"]["objects"][0]["file"] = "assets/nowhere.obj";
  expect_rejected(test::make_job_spec(missing_model.dump(), test::cornell_assets(), "cornell.json"),
                  grpc::StatusCode::INVALID_ARGUMENT, "nowhere.obj");

  nlohmann::json bad_camera = nlohmann::json::parse(test::cornell_job_json("whitted", 32, 32, 1));
  bad_camera["scene"]["camera"]["target"] = {0, 0, 3.9};  // the camera's own position
  expect_rejected(test::make_job_spec(bad_camera.dump(), test::cornell_assets(), "cornell.json"),
                  grpc::StatusCode::INVALID_ARGUMENT, "scene.camera");

  v1::JobSpec not_uploaded = cornell("raster", 32, 32, 1, 16);
  not_uploaded.mutable_assets(0)->set_sha256(std::string(64, 'f'));
  expect_rejected(not_uploaded, grpc::StatusCode::FAILED_PRECONDITION, "cornell_box.obj");

  const v1::Job good = submit_ok(cornell("raster", 32, 32, 1, 16));
  const auto final_job = test::wait_for_job(*stub_, good.job_id(), done, 30s);
  ASSERT_TRUE(final_job);
  EXPECT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();

  v1::GetJobRequest unknown;
  unknown.set_job_id("nope");
  grpc::ClientContext context;
  v1::Job job;
  EXPECT_EQ(stub_->GetJob(&context, unknown, &job).error_code(), grpc::StatusCode::NOT_FOUND);
}

// Requests that would start more work than one job should (measured at an older HEAD: 16384x16384
// at tile_size 1 made the scheduler unresponsive at 4.4 GB; 4096x4096 at tile_size 1 took 51 s to
// submit and 2.1 GB of database; embree_rays 1e12 grew it by 170 MB/s at the merge; a 50 MB job
// text was accepted and sent with every tile; a 300-byte name rendered every tile, then failed at
// the merge) are refused at submit with a message naming the limit and the value, nothing of
// them is stored, and the next honest job renders.
TEST_F(FarmSchedulerTest, WorkBombsAreRefusedAtSubmitAndTheFarmKeepsServing) {
  auto worker = start_worker("w1");
  auto scheduler = start_scheduler({"--worker", worker->address()});
  ASSERT_TRUE(stub_);
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  const auto expect_refused = [&](const v1::JobSpec& spec, grpc::StatusCode code,
                                  const std::vector<std::string>& needles) {
    v1::Job job;
    const grpc::Status status = test::submit(*stub_, spec, job);
    EXPECT_EQ(status.error_code(), code) << status.error_message();
    for (const std::string& needle : needles) {
      EXPECT_NE(status.error_message().find(needle), std::string::npos)
          << "no '" << needle << "' in: " << status.error_message();
    }
  };
  const auto with = [](const std::function<void(nlohmann::json&)>& change) {
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("raster", 32, 32, 1));
    change(job);
    return test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json");
  };

  expect_refused(cornell("raster", 16384, 16384, 1, 1), grpc::StatusCode::RESOURCE_EXHAUSTED,
                 {"cornell.json", "render.tile_size", "268435456 units", "at most 65536",
                  "--max-tiles-per-job"});
  expect_refused(cornell("raster", 4096, 4096, 1, 1), grpc::StatusCode::RESOURCE_EXHAUSTED,
                 {"16777216 units", "--max-tiles-per-job"});
  expect_refused(cornell("path", 16384, 16384, kMaxSpp, 128), grpc::StatusCode::RESOURCE_EXHAUSTED,
                 {"render", "1048576 spp", "--max-work"});
  expect_refused(with([](nlohmann::json& j) { j["validate"]["embree_rays"] = 50'000'000; }),
                 grpc::StatusCode::RESOURCE_EXHAUSTED,
                 {"validate.embree_rays", "50000000 rays", "at most 10000000", "--max-embree-rays"});
  // Beyond what any job may ask (job_limits.h: farm render too).
  expect_refused(with([](nlohmann::json& j) { j["validate"]["embree_rays"] = 1'000'000'000'000; }),
                 grpc::StatusCode::INVALID_ARGUMENT, {"validate.embree_rays", "<= 100000000"});
  // Raw, past the client's own 16 MiB check, under the scheduler's 64 MiB message limit.
  v1::JobSpec fat = cornell("raster", 32, 32, 1, 16);
  fat.set_job_json(fat.job_json() + std::string(50 << 20, ' '));
  expect_refused(fat, grpc::StatusCode::RESOURCE_EXHAUSTED,
                 {std::to_string(fat.job_json().size()) + " bytes", "at most 16777216", "--max-job-bytes"});
  expect_refused(with([](nlohmann::json& j) { j["name"] = std::string(300, 'n'); }),
                 grpc::StatusCode::INVALID_ARGUMENT, {"cornell.json: name:", "300 bytes", "at most 200"});

  // Nothing of them was stored: no job, no tile rows.
  {
    grpc::ClientContext context;
    v1::ListJobsResponse jobs;
    ASSERT_TRUE(stub_->ListJobs(&context, v1::ListJobsRequest(), &jobs).ok());
    EXPECT_EQ(jobs.jobs_size(), 0);
  }
  std::uintmax_t database = 0;
  for (const auto& entry : fs::directory_iterator(dir_ / "data")) {
    if (entry.path().filename().string().starts_with("jobs.db")) database += entry.file_size();
  }
  EXPECT_LT(database, std::uintmax_t{4} << 20);

  const v1::Job good = submit_ok(cornell("raster", 32, 32, 1, 16));
  const auto final_job = test::wait_for_job(*stub_, good.job_id(), done, 30s);
  ASSERT_TRUE(final_job);
  EXPECT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();
}

// A model whose loading would hold a scheduler thread is refused, and the scheduler keeps serving:
// a 187-byte PLY that declares 10M faces (it used to run minutes at 1.5 GB) by its header check;
// a model within every byte limit that takes long to triangulate, or memory to load, by the
// budget of the child process SubmitJob loads scenes in. That child never outlives the call.
TEST_F(FarmSchedulerTest, ModelBombsAreRefusedWithinTheSceneBudgetAndTheSchedulerKeepsServing) {
  auto worker = start_worker("w1");
  auto scheduler = start_scheduler({"--worker", worker->address(), "--max-scene-seconds", "3",
                                    "--max-scene-memory", std::to_string(256 << 20)});
  ASSERT_TRUE(stub_);
  const auto refusal = [&](const std::string& name, const fs::path& model) {
    const std::vector<std::pair<std::string, fs::path>> files{{name, model}};
    EXPECT_TRUE(test::upload_assets(*stub_, files).ok());
    const v1::JobSpec spec = test::make_job_spec(
        R"({"version": 1, "name": "bomb", "scene": {"objects": [{"file": ")" + name +
            R"("}]}, "render": {"engine": "raster", "width": 16, "height": 16}})",
        files, "bomb.json");
    v1::Job job;
    return test::submit(*stub_, spec, job);
  };

  std::ofstream(dir_ / "faces.ply")
      << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 10000000\nproperty list uchar int vertex_indices\n"
         "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const grpc::Status faces = refusal("faces.ply", dir_ / "faces.ply");
  EXPECT_EQ(faces.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << faces.error_message();
  EXPECT_NE(faces.error_message().find("bomb.json: scene.objects[0].file: faces.ply: the PLY header "
                                       "declares 10000000 'face' elements"),
            std::string::npos) << faces.error_message();

  write_slow_model(dir_ / "slow.obj");
  const grpc::Status slow = refusal("slow.obj", dir_ / "slow.obj");
  EXPECT_EQ(slow.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << slow.error_message();
  EXPECT_NE(slow.error_message().find("bomb.json: loading the job's models and building its scene took "
                                      "longer than 3 s, the scheduler's limit (--max-scene-seconds)"),
            std::string::npos) << slow.error_message();

  {  // 640,000 honest quads: 26 MB of text that takes about 350 MiB of memory to load
    std::ofstream out(dir_ / "grid.obj");
    constexpr int kSide = 800;
    for (int j = 0; j < kSide; ++j)
      for (int i = 0; i < kSide; ++i) out << "v " << i << ' ' << j << " 0\n";
    for (int j = 0; j + 1 < kSide; ++j)
      for (int i = 0; i + 1 < kSide; ++i) {
        const int a = j * kSide + i + 1;
        out << "f " << a << ' ' << a + 1 << ' ' << a + kSide + 1 << ' ' << a + kSide << '\n';
      }
  }
  const grpc::Status big = refusal("grid.obj", dir_ / "grid.obj");
  EXPECT_EQ(big.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << big.error_message();
  EXPECT_NE(big.error_message().find("bomb.json: loading the job's models and building its scene needs "
                                     "more than 0.25 GiB of memory, the scheduler's limit (--max-scene-memory)"),
            std::string::npos) << big.error_message();

  // No job was stored and no checking process is left behind.
  {
    grpc::ClientContext context;
    v1::ListJobsResponse jobs;
    ASSERT_TRUE(stub_->ListJobs(&context, v1::ListJobsRequest(), &jobs).ok());
    EXPECT_EQ(jobs.jobs_size(), 0);
  }
  EXPECT_EQ(test::children_of(scheduler->process().pid()), 0u);

  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  const v1::Job good = submit_ok(cornell("raster", 32, 32, 1, 16));
  const auto final_job = test::wait_for_job(*stub_, good.job_id(), done, 30s);
  ASSERT_TRUE(final_job);
  EXPECT_EQ(final_job->state(), v1::JOB_STATE_SUCCEEDED) << final_job->failure_reason();
}

// Each scene check holds a core for up to its time budget: a burst of slow models gets at most
// --max-scene-checks of them at once, the others wait for a slot (or are refused when none comes).
TEST_F(FarmSchedulerTest, SlowModelsSubmittedTogetherAreCheckedOneAtATime) {
  auto scheduler = start_scheduler({"--max-scene-seconds", "4", "--max-scene-checks", "1"});
  ASSERT_TRUE(stub_);
  write_slow_model(dir_ / "slow.obj");
  const std::vector<std::pair<std::string, fs::path>> files{{"slow.obj", dir_ / "slow.obj"}};
  ASSERT_TRUE(test::upload_assets(*stub_, files).ok());
  std::vector<grpc::Status> statuses(3);
  std::atomic<std::size_t> finished{0};
  std::vector<std::thread> submits;
  for (std::size_t i = 0; i < statuses.size(); ++i) {
    submits.emplace_back([&, i] {
      // Three different scenes (the names differ), so none is a check another already passed.
      const v1::JobSpec spec = test::make_job_spec(
          R"({"version": 1, "name": "slow)" + std::to_string(i) +
              R"(", "scene": {"objects": [{"file": "slow.obj"}]}, "render": {"engine": "raster", "width": 16, "height": 16}})",
          files, "slow.json");
      v1::Job job;
      statuses[i] = test::submit(*stub_, spec, job);
      ++finished;
    });
  }
  // Sampling can miss a moment with two children, never invent one.
  std::size_t most_children = 0;
  while (finished < statuses.size()) {
    most_children = std::max(most_children, test::children_of(scheduler->process().pid()));
    std::this_thread::sleep_for(20ms);
  }
  for (std::thread& t : submits) t.join();
  EXPECT_EQ(most_children, 1u);
  for (const grpc::Status& status : statuses) {
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  }
  EXPECT_EQ(test::children_of(scheduler->process().pid()), 0u);
}

// The limits are the operator's: `farm scheduler --max-...` moves them.
TEST_F(FarmSchedulerTest, SchedulerFlagsSetTheSubmitLimits) {
  auto scheduler = start_scheduler({"--max-tiles-per-job", "4", "--max-job-bytes", "100000",
                                    "--max-embree-rays", "0", "--max-work", "5000",
                                    "--max-asset-store-bytes", "100000"});
  ASSERT_TRUE(stub_);
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  {  // The Cornell box's files are a few kB; 100 kB more would pass the store's limit.
    std::ofstream(dir_ / "big.bin") << std::string(100000, 'b');
    const grpc::Status full = test::upload_assets(*stub_, {{"big.bin", dir_ / "big.bin"}});
    EXPECT_EQ(full.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << full.error_message();
    EXPECT_NE(full.error_message().find("asset of 100000 bytes: the scheduler's asset store holds "),
              std::string::npos) << full.error_message();
    EXPECT_NE(full.error_message().find("of at most 100000 (--max-asset-store-bytes)"), std::string::npos)
        << full.error_message();
    EXPECT_FALSE(fs::exists(dir_ / "data" / "assets" / sha256_hex(std::string(100000, 'b'))));
  }
  const auto refusal = [&](const v1::JobSpec& spec) {
    v1::Job job;
    const grpc::Status status = test::submit(*stub_, spec, job);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
    return status.error_message();
  };
  EXPECT_NE(refusal(cornell("raster", 64, 64, 1, 16)).find("16 units; the scheduler takes at most 4 "),
            std::string::npos);
  EXPECT_NE(refusal(cornell("raster", 64, 64, 2, 32)).find("at most 5e+03 a job (--max-work)"),
            std::string::npos);
  v1::JobSpec fat = cornell("raster", 64, 64, 1, 32);
  fat.set_job_json(fat.job_json() + std::string(100000, ' '));
  EXPECT_NE(refusal(fat).find("at most 100000 (--max-job-bytes)"), std::string::npos);
  nlohmann::json rays = nlohmann::json::parse(test::cornell_job_json("raster", 64, 64, 1));
  rays["render"]["tile_size"] = 32;
  rays["validate"]["embree_rays"] = 1;
  EXPECT_NE(refusal(test::make_job_spec(rays.dump(), test::cornell_assets(), "cornell.json"))
                .find("at most 0 a job (--max-embree-rays)"),
            std::string::npos);
  submit_ok(cornell("raster", 64, 64, 1, 32));  // 4 tiles, 4096 samples: within every one
}

TEST_F(FarmSchedulerTest, PythonClientPackageInstalledWithPipSubmitsWatchesAndFetches) {
  // Another language speaking the wire contract: the farm_client package (proto/python), built by
  // pip into a fresh venv with its stubs generated from proto/farm.proto at build time (Debian's
  // python3-grpc-tools), finds the job's assets itself as `farm submit` does, uploads, submits,
  // watches and fetches (tests/python/farm_client_package_check.py); the EXR it gets equals the one
  // the C++ client fetches. The scheduler asks for tokens (#15): refused without one.
  const std::string token = "python-client-token-0123456789", admin = "test-admin-token-0123456789";
  const fs::path tokens = dir_ / "tokens.txt";
  std::ofstream(tokens) << sha256_hex(token) << " py submit\n" << sha256_hex(admin) << " tests admin\n";
  const fs::path token_file = dir_ / "py-token.txt";
  std::ofstream(token_file) << token << "\n";
  auto worker = start_worker("w1", 2);
  auto scheduler = start_scheduler({"--worker", worker->address(), "--tokens", tokens.string()});
  ASSERT_TRUE(stub_);
  stub_ = test::scheduler_stub(scheduler->address(), ClientIdentity{admin, false, {}});

  // Built from a copy of the source folder, which the build must leave as it was (issue #32: pip's
  // in-tree build wrote build/ and farm_client.egg-info/ into it).
  const fs::path source = dir_ / "src" / "proto";
  fs::create_directories(source);
  fs::copy(test::kSource / "proto/python", source / "python", fs::copy_options::recursive);
  fs::copy_file(test::kSource / "proto/farm.proto", source / "farm.proto");
  const auto listing = [&] {
    std::vector<std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(source)) files.push_back(fs::relative(e.path(), source).string());
    std::sort(files.begin(), files.end());
    return files;
  };
  const std::vector<std::string> before = listing();
  const fs::path venv = dir_ / "venv";
  const test::CommandResult made = test::run_command(
      "/usr/bin/python3 -m venv --system-site-packages " + test::shell_quote(venv.string()) + " && " +
      test::shell_quote((venv / "bin/pip").string()) + " install --quiet --no-build-isolation --no-index " +
      test::shell_quote((source / "python").string()));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  EXPECT_EQ(listing(), before) << "the build wrote into the source folder";
  const test::CommandResult where = test::run_command(
      test::shell_quote((venv / "bin/python").string()) + " -c 'import farm_client._gen.farm_pb2 as m; print(m.__file__)'");
  ASSERT_EQ(where.exit_code, 0) << where.output;
  EXPECT_NE(where.output.find(venv.string()), std::string::npos) << "stubs generated into the installed package: " << where.output;
  // A plan from another process is checked before the package acts on it: fake schedulers that
  // ask for paths out of the root, ask twice, ask for nothing, or predate PlanSubmission.
  const test::CommandResult distrust = test::run_command(
      test::shell_quote((venv / "bin/python").string()) + " " +
      test::shell_quote((test::kSource / "tests/python/farm_client_plan_check.py").string()));
  EXPECT_EQ(distrust.exit_code, 0) << distrust.output;

  // The job file in a folder with its model and materials, as a user has them.
  const v1::JobSpec spec = cornell("raster", 48, 32, 1, 16);
  const fs::path job = dir_ / "job" / "cornell.json";
  fs::create_directories(job.parent_path() / "assets");
  std::ofstream(job) << spec.job_json();
  for (const auto& [path, file] : test::cornell_assets()) fs::copy_file(file, job.parent_path() / path);
  const fs::path out = dir_ / "python-out";
  const std::string command = test::shell_quote((venv / "bin/python").string()) + " " +
                              test::shell_quote((test::kSource / "tests/python/farm_client_package_check.py").string()) +
                              " --scheduler " + scheduler->address() + " --job " + test::shell_quote(job.string()) +
                              " --out " + test::shell_quote(out.string());
  const test::CommandResult refused = test::run_command(command);
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_NE(refused.output.find("UNAUTHENTICATED"), std::string::npos) << refused.output;
  const test::CommandResult r = test::run_command(command + " --token-file " + test::shell_quote(token_file.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json result = last_json_line(r.output);
  EXPECT_EQ(result["state"], "SUCCEEDED") << r.output;
  EXPECT_EQ(result["uploaded"], 2) << r.output;  // the model and its material library, found by the scheduler
  EXPECT_TRUE(result["listed"].get<bool>()) << r.output;
  EXPECT_GT(result["events"].get<int>(), 1) << r.output;
  EXPECT_EQ(differing_pixels(read_exr(result["exr"].get<std::string>()), fetch_exr(result["job_id"])), 0);

  // #33: the package reads no model format; the scheduler says what each model names
  // (PlanSubmission). An OBJ whose library names a texture (and a bump map that is not there), and
  // a glTF with an external buffer: exactly their files are uploaded, and the jobs render.
  const auto check = [&](const fs::path& job_file, const std::string& options = "") {
    const test::CommandResult run = test::run_command(
        test::shell_quote((venv / "bin/python").string()) + " " +
        test::shell_quote((test::kSource / "tests/python/farm_client_package_check.py").string()) + " --scheduler " +
        scheduler->address() + " --job " + test::shell_quote(job_file.string()) + " --out " +
        test::shell_quote((dir_ / "python-out-2").string()) + " --token-file " + test::shell_quote(token_file.string()) +
        options);
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return last_json_line(run.output);
  };
  const fs::path textured = dir_ / "textured";
  fs::create_directories(textured / "assets/tex");
  std::string obj = test::read_file(test::kSource / "jobs/assets/cornell_box.obj");
  obj.replace(obj.find("mtllib cornell_box.mtl"), 22, "mtllib box.mtl");
  std::ofstream(textured / "assets/box.obj") << obj;
  std::ofstream(textured / "assets/box.mtl") << test::read_file(test::kSource / "jobs/assets/cornell_box.mtl")
                                              << "map_Kd tex/wood.png\nbump tex/none.png\n";
  fs::copy_file(test::kSource / "jobs/assets/checker.png", textured / "assets/tex/wood.png");
  std::string job_text = spec.job_json();
  job_text.replace(job_text.find("assets/cornell_box.obj"), 22, "assets/box.obj");
  std::ofstream(textured / "textured.json") << job_text;
  nlohmann::json planned = check(textured / "textured.json");
  EXPECT_EQ(planned["state"], "SUCCEEDED") << planned;
  EXPECT_EQ(planned["asset_paths"], nlohmann::json({"assets/box.mtl", "assets/box.obj", "assets/tex/wood.png"}));
  EXPECT_EQ(planned["absent"], nlohmann::json({"assets/tex/none.png"}));
  EXPECT_EQ(planned["uploaded"], 3) << planned;
  // Two rounds a level while the scheduler lacks the files (the model, its library, the map: each
  // uploaded, then read), one a level once it holds them.
  EXPECT_EQ(planned["rounds"], 6) << planned;
  planned = check(textured / "textured.json", " --prepare-only");
  EXPECT_EQ(planned["uploaded"], 0) << planned;
  EXPECT_EQ(planned["rounds"], 3) << planned;

  const fs::path gltf = dir_ / "gltf";
  fs::create_directories(gltf / "assets");
  const test::CommandResult split = test::run_command(
      "/usr/bin/python3 -c 'import base64, json, sys; d = json.load(open(sys.argv[1])); b = d[\"buffers\"][0]; "
      "open(sys.argv[2] + \"/torus.bin\", \"wb\").write(base64.b64decode(b[\"uri\"].split(\",\", 1)[1])); "
      "b[\"uri\"] = \"torus.bin\"; json.dump(d, open(sys.argv[2] + \"/torus.gltf\", \"w\"))' " +
      test::shell_quote((test::kSource / "jobs/assets/torus.gltf").string()) + " " +
      test::shell_quote((gltf / "assets").string()));
  ASSERT_EQ(split.exit_code, 0) << split.output;
  nlohmann::json torus = nlohmann::json::parse(test::read_file(test::kSource / "jobs/torus.json"));
  torus["render"]["width"] = 48;
  torus["render"]["height"] = 32;
  std::ofstream(gltf / "torus.json") << torus.dump(2);
  planned = check(gltf / "torus.json");
  EXPECT_EQ(planned["state"], "SUCCEEDED") << planned;
  EXPECT_EQ(planned["asset_paths"], nlohmann::json({"assets/torus.bin", "assets/torus.gltf"}));
  EXPECT_EQ(planned["uploaded"], 2) << planned;
  EXPECT_EQ(planned["rounds"], 4) << planned;
}

}  // namespace
}  // namespace farm
