// Workers are not trusted: a real `farm scheduler` with lying workers (tests/support/fake_worker.h)
// beside honest ones. Malformed replies never reach the image and their workers are quarantined;
// spot checks (--verify-fraction) catch a worker whose pixels only look right; forged pixels
// accepted before their worker was caught are rendered again. And RegisterWorker, called a
// thousand times, leaves the scheduler's threads and memory flat. Every wait is bounded; nothing
// asserts on wall-clock time.
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <signal.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "renderer/image/exr_io.h"
#include "server/common/asset_store.h"
#include "tests/support/eventually.h"
#include "tests/support/background_process.h"
#include "tests/support/fake_worker.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using test::eventually;

namespace fs = std::filesystem;
using namespace std::chrono_literals;

bool final_state(const v1::Job& job) {
  return job.state() == v1::JOB_STATE_SUCCEEDED || job.state() == v1::JOB_STATE_FAILED ||
         job.state() == v1::JOB_STATE_CANCELLED;
}

// Waits (bounded) until `done()`; false when it never came.
bool same_bits(const void* a, const void* b, std::size_t n) { return std::memcmp(a, b, n) == 0; }

// Pixels whose bits differ in any channel; -1 when the images do not even cover the same rect.
int differing_pixels(const TileBuffer& a, const TileBuffer& b) {
  if (!(a.rect() == b.rect()) || a.rect().empty()) return -1;
  int differing = 0;
  for (int y = a.rect().y0; y < a.rect().y1; ++y) {
    for (int x = a.rect().x0; x < a.rect().x1; ++x) {
      const float da = a.aovs().depth ? a.depth(x, y) : 0.0f, db = b.aovs().depth ? b.depth(x, y) : 0.0f;
      const float ca = a.aovs().bvh_cost ? a.bvh_cost(x, y) : 0.0f, cb = b.aovs().bvh_cost ? b.bvh_cost(x, y) : 0.0f;
      if (!same_bits(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)) || !same_bits(&da, &db, sizeof da) ||
          !same_bits(&ca, &cb, sizeof ca) ||
          (a.aovs().normal && !same_bits(&a.normal(x, y), &b.normal(x, y), sizeof(glm::vec3))) ||
          (a.aovs().albedo && !same_bits(&a.albedo(x, y), &b.albedo(x, y), sizeof(glm::vec3))) ||
          (a.aovs().variance && !same_bits(&a.variance(x, y), &b.variance(x, y), sizeof(glm::vec3)))) {
        ++differing;
      }
    }
  }
  return differing;
}

// What an image holds that no engine writes: the figures of the issue (Z = -3e38, normals of
// 22048, infinities), for failure messages.
std::string oddities(const TileBuffer& t) {
  if (t.rect().empty()) return "no image";
  float min_z = INFINITY, max_normal = 0.0f;
  int non_finite_rgba = 0;
  for (int y = t.rect().y0; y < t.rect().y1; ++y) {
    for (int x = t.rect().x0; x < t.rect().x1; ++x) {
      const glm::vec4& c = t.rgba(x, y);
      if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z) || !std::isfinite(c.w)) ++non_finite_rgba;
      if (t.aovs().depth && !(t.depth(x, y) >= min_z)) min_z = t.depth(x, y);
      if (t.aovs().normal) {
        const glm::vec3& n = t.normal(x, y);
        max_normal = std::max({max_normal, std::fabs(n.x), std::fabs(n.y), std::fabs(n.z)});
      }
    }
  }
  std::ostringstream s;
  s << "min Z " << min_z << ", largest normal component " << max_normal << ", " << non_finite_rgba
    << " pixels with a non-finite RGBA value";
  return s.str();
}

class UntrustedWorkersTest : public ::testing::Test {
 protected:
  // The path-traced Cornell box with depth, normal, albedo and variance, in 8 px tiles: 24 units
  // with --batch-ms 0.
  v1::JobSpec job_spec() const {
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("path", 48, 32, 2));
    job["render"]["tile_size"] = 8;
    return test::make_job_spec(job.dump(2), test::cornell_assets(), "cornell.json");
  }

  // A fake worker whose cache holds the Cornell box's files already: no call of it is refused
  // for want of them (which would be a TileFailed naming it before any lie).
  std::unique_ptr<test::FakeWorker> fake_worker(const std::string& name, test::Lie lie = test::Lie::None) {
    const AssetStore blobs(dir_ / name / "blobs");
    for (const auto& [path, file] : test::cornell_assets()) blobs.add(test::read_file(file));
    return std::make_unique<test::FakeWorker>(dir_ / name, lie);
  }

  void start_scheduler(std::vector<std::string> args) {
    scheduler_ = std::make_unique<test::SchedulerProcess>(dir_ / "data", args);
    ASSERT_FALSE(scheduler_->address().empty()) << scheduler_->process().output();
    stub_ = test::scheduler_stub(scheduler_->address());
  }

  std::string submit(const v1::JobSpec& spec) {
    EXPECT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
    v1::Job job;
    const grpc::Status status = test::submit(*stub_, spec, job);
    EXPECT_TRUE(status.ok()) << status.error_message();
    // Every event of the job from the watch's start until the job is final. Events published
    // before WatchJob subscribes are not sent: workers that must be seen wait (hold_after) until
    // watching() says the snapshot came.
    watcher_ = std::thread([this, id = job.job_id()] {
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + 180s);
      v1::WatchJobRequest request;
      request.set_job_id(id);
      auto reader = stub_->WatchJob(&context, request);
      v1::JobEvent event;
      while (reader->Read(&event)) {
        std::lock_guard lock(events_mutex_);
        events_.push_back(event);
      }
      reader->Finish();
    });
    return job.job_id();
  }

  // Waits for the watch's snapshot: every event from now on is seen.
  bool watching() {
    return eventually([&] {
      std::lock_guard lock(events_mutex_);
      return !events_.empty();
    });
  }

  // Waits for the job to end; its events are in events_ after this.
  v1::Job finish(const std::string& id) {
    const std::optional<v1::Job> job = test::wait_for_job(*stub_, id, final_state, 180s);
    if (watcher_.joinable()) watcher_.join();
    EXPECT_TRUE(job) << "job " << id << " never ended\n" << scheduler_->process().output();
    return job ? *job : v1::Job();
  }

  // A `farm worker` that registers with the scheduler and fetches the job's files from it.
  std::unique_ptr<test::WorkerProcess> start_honest_worker(const std::string& name) {
    auto worker = std::make_unique<test::WorkerProcess>(std::vector<std::string>{
        "--threads", "1", "--cache-dir", (dir_ / name).string(), "--scheduler", scheduler_->address()});
    EXPECT_FALSE(worker->address().empty()) << worker->process().output();
    EXPECT_TRUE(worker->process().wait_for_line("registered with the scheduler", 30s)) << worker->process().output();
    return worker;
  }

  // The job's EXR from the scheduler, and `farm render --float` of the same job file.
  std::pair<TileBuffer, TileBuffer> farm_and_local_images(const std::string& id, const v1::JobSpec& spec) {
    const fs::path fetched = dir_ / (id + ".exr");
    const grpc::Status status = test::fetch_result(*stub_, id, v1::RESULT_KIND_EXR, fetched);
    EXPECT_TRUE(status.ok()) << status.error_message();
    const fs::path job_dir = dir_ / "local-job";
    fs::create_directories(job_dir / "assets");
    for (const auto& [path, file] : test::cornell_assets()) fs::copy_file(file, job_dir / path, fs::copy_options::overwrite_existing);
    std::ofstream(job_dir / "cornell.json") << spec.job_json();
    const fs::path local = dir_ / "local.exr";
    const test::CommandResult r = test::run_command(test::farm_command(
        "render " + test::shell_quote((job_dir / "cornell.json").string()) + " --float --quiet --out " +
        test::shell_quote(local.string()) + " --preview none"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return {status.ok() ? read_exr(fetched) : TileBuffer(), r.exit_code == 0 ? read_exr(local) : TileBuffer()};
  }

  // The TileFailed events that name `address` as the worker, with their reasons.
  std::vector<std::string> failures_of(const std::string& address) const {
    std::vector<std::string> reasons;
    for (const v1::JobEvent& e : events_) {
      if (e.has_tile_failed() && e.tile_failed().worker() == address) reasons.push_back(e.tile_failed().reason());
    }
    return reasons;
  }

  bool quarantined(const std::string& address) {
    return scheduler_->process().output().find(address + " quarantined") != std::string::npos;
  }

  void TearDown() override {
    if (watcher_.joinable()) watcher_.join();
  }

  test::TempDir dir_;
  std::unique_ptr<test::SchedulerProcess> scheduler_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
  std::thread watcher_;
  std::mutex events_mutex_;
  std::vector<v1::JobEvent> events_;  // read without the mutex once watcher_ is joined
};

// Replies a worker can send that no engine ever makes. Each is refused before anything of it is
// stored, its tile goes to another worker, and its worker gets no more. The job finishes on the
// honest worker that joins once every liar has been caught, bit-identical to `farm render`.
TEST_F(UntrustedWorkersTest, MalformedRepliesNeverReachTheImageAndTheirWorkersAreQuarantined) {
  const std::vector<std::pair<test::Lie, std::string>> lies{
      {test::Lie::ShiftedRect, "rect"},
      {test::Lie::MissingPlane, "normal plane"},
      {test::Lie::ExtraPlane, "bvh_cost plane"},
      {test::Lie::ShortPlane, "depth plane"},
      {test::Lie::NaN, "NaN"},
      {test::Lie::NegativeDepth, "depth"},
  };
  std::vector<std::unique_ptr<test::FakeWorker>> liars;
  std::vector<std::string> args{"--float", "--batch-ms", "0", "--max-attempts", "20"};
  for (const auto& [lie, what] : lies) {
    liars.push_back(fake_worker(test::to_string(lie), lie));
    ASSERT_FALSE(liars.back()->address().empty());
    liars.back()->hold_after(0);  // until the job is watched
    args.insert(args.end(), {"--worker", liars.back()->address()});
  }
  ASSERT_NO_FATAL_FAILURE(start_scheduler(args));
  const v1::JobSpec spec = job_spec();
  const std::string id = submit(spec);
  ASSERT_TRUE(watching());
  for (const auto& liar : liars) liar->release();

  // Every liar gets tiles (the job cannot finish without an honest worker) and is caught.
  const auto caught = [&](std::size_t i) { return liars[i]->lies_told() > 0 && quarantined(liars[i]->address()); };
  eventually([&] {
    for (std::size_t i = 0; i < liars.size(); ++i) {
      if (!caught(i)) return false;
    }
    return true;
  });
  for (std::size_t i = 0; i < liars.size(); ++i) {
    EXPECT_TRUE(caught(i)) << to_string(lies[i].first) << " was never caught\n" << scheduler_->process().output();
  }
  const auto honest = start_honest_worker("honest");
  const v1::Job job = finish(id);
  ASSERT_EQ(job.state(), v1::JOB_STATE_SUCCEEDED) << job.failure_reason();

  const auto [farm_image, local_image] = farm_and_local_images(id, spec);
  EXPECT_EQ(differing_pixels(farm_image, local_image), 0) << oddities(farm_image);
  for (std::size_t i = 0; i < liars.size(); ++i) {
    // A caught worker answers no more calls: its one lie (per slot) was its last.
    EXPECT_LE(liars[i]->calls_answered(), 2) << to_string(lies[i].first);
    const std::vector<std::string> reasons = failures_of(liars[i]->address());
    ASSERT_FALSE(reasons.empty()) << to_string(lies[i].first) << " is named in no TileFailed event";
    EXPECT_NE(reasons.front().find(liars[i]->address() + " sent a result no engine makes"), std::string::npos)
        << reasons.front();
    EXPECT_NE(reasons.front().find(lies[i].second), std::string::npos) << reasons.front();
  }
}

// Pixels that look right pass the checks; with no spot checks they are kept. When their worker is
// caught later (here: a NaN), what it rendered for unfinished jobs is thrown away and rendered
// again, so the image is still bit-identical to `farm render`.
// Not about trust, but this fixture has the worker that counts what it is sent: a job's text
// travels with the first calls to a worker, not with all 24; a worker that lost the scene answers
// NOT_FOUND and is sent the job again, with no failure counted and the same pixels.
TEST_F(UntrustedWorkersTest, TheJobTextTravelsOncePerWorkerAndAgainToOneThatLostTheScene) {
  const auto fake = fake_worker("w");
  test::FakeWorker& worker = *fake;
  ASSERT_FALSE(worker.address().empty());
  ASSERT_NO_FATAL_FAILURE(start_scheduler({"--float", "--batch-ms", "0", "--worker", worker.address()}));
  const v1::JobSpec spec = job_spec();
  const v1::Job first = finish(submit(spec));
  ASSERT_EQ(first.state(), v1::JOB_STATE_SUCCEEDED) << first.failure_reason();
  // The first calls go out together (--tiles-per-worker 2), before the worker has answered one.
  EXPECT_GE(worker.calls_received(), 24);
  const int sent = worker.calls_with_job();
  EXPECT_GE(sent, 1);
  EXPECT_LE(sent, 2);
  EXPECT_EQ(worker.job_text_bytes(), sent * spec.job_json().size());

  worker.forget_scenes_for(1);
  const std::string id = submit(spec);
  const v1::Job second = finish(id);
  ASSERT_EQ(second.state(), v1::JOB_STATE_SUCCEEDED) << second.failure_reason();
  EXPECT_EQ(worker.calls_with_job(), sent + 1);
  EXPECT_EQ(second.tiles_rendered(), second.tiles_total());
  EXPECT_TRUE(failures_of(worker.address()).empty());
  const auto [farm_image, local_image] = farm_and_local_images(id, spec);
  EXPECT_EQ(differing_pixels(farm_image, local_image), 0);
}

TEST_F(UntrustedWorkersTest, ForgedPixelsKeptBeforeTheirWorkerWasCaughtAreRenderedAgain) {
  const auto fake = fake_worker("liar", test::Lie::FlippedBits);
  test::FakeWorker& liar = *fake;
  ASSERT_FALSE(liar.address().empty());
  liar.hold_after(0);  // until the job is watched
  ASSERT_NO_FATAL_FAILURE(start_scheduler({"--float", "--batch-ms", "0", "--worker", liar.address()}));
  const v1::JobSpec spec = job_spec();
  const std::string id = submit(spec);
  ASSERT_TRUE(watching());
  liar.hold_after(1);  // one forged reply, then the others wait
  ASSERT_TRUE(test::wait_for_job(*stub_, id, [](const v1::Job& j) { return j.tiles_done() >= 1; }, 60s))
      << scheduler_->process().output();
  liar.set_lie(test::Lie::NaN);
  liar.release();
  ASSERT_TRUE(eventually([&] { return quarantined(liar.address()); })) << scheduler_->process().output();

  const auto honest = start_honest_worker("honest");
  const v1::Job job = finish(id);
  ASSERT_EQ(job.state(), v1::JOB_STATE_SUCCEEDED) << job.failure_reason();
  const auto [farm_image, local_image] = farm_and_local_images(id, spec);
  EXPECT_EQ(differing_pixels(farm_image, local_image), 0);
  // The forged tile was accepted once and rendered again.
  EXPECT_GT(job.tiles_rendered(), job.tiles_total());
  bool discarded = false;
  for (const std::string& reason : failures_of(liar.address())) {
    discarded = discarded || reason.find("discarded") != std::string::npos;
  }
  EXPECT_TRUE(discarded) << "no TileFailed event says the liar's kept tile was discarded";
}

// Every unit is rendered twice (--verify-fraction 1); the liar's pixels disagree with an honest
// worker's, a third opinion decides, and the liar is quarantined. The honest workers wait until
// the liar has answered, so that it certainly takes part.
TEST_F(UntrustedWorkersTest, SpotChecksCatchAWorkerWhosePixelsOnlyLookRight) {
  const auto fakes = std::array{fake_worker("liar", test::Lie::FlippedBits), fake_worker("honest1"), fake_worker("honest2")};
  test::FakeWorker &liar = *fakes[0], &honest1 = *fakes[1], &honest2 = *fakes[2];
  ASSERT_FALSE(liar.address().empty() || honest1.address().empty() || honest2.address().empty());
  honest1.hold_after(0);
  honest2.hold_after(0);
  ASSERT_NO_FATAL_FAILURE(start_scheduler({"--float", "--batch-ms", "0", "--verify-fraction", "1", "--worker",
                                           liar.address(), "--worker", honest1.address(), "--worker",
                                           honest2.address()}));
  const v1::JobSpec spec = job_spec();
  const std::string id = submit(spec);
  ASSERT_TRUE(watching());
  ASSERT_TRUE(eventually([&] { return liar.lies_told() > 0; })) << scheduler_->process().output();
  honest1.release();
  honest2.release();

  const v1::Job job = finish(id);
  ASSERT_EQ(job.state(), v1::JOB_STATE_SUCCEEDED) << job.failure_reason() << scheduler_->process().output();
  const auto [farm_image, local_image] = farm_and_local_images(id, spec);
  EXPECT_EQ(differing_pixels(farm_image, local_image), 0);
  EXPECT_TRUE(quarantined(liar.address())) << scheduler_->process().output();
  EXPECT_FALSE(quarantined(honest1.address())) << scheduler_->process().output();
  EXPECT_FALSE(quarantined(honest2.address())) << scheduler_->process().output();
  const std::vector<std::string> reasons = failures_of(liar.address());
  ASSERT_FALSE(reasons.empty()) << "the liar is named in no TileFailed event";
  EXPECT_NE(reasons.front().find(liar.address()), std::string::npos) << reasons.front();
  EXPECT_TRUE(failures_of(honest1.address()).empty());
  EXPECT_TRUE(failures_of(honest2.address()).empty());
}

// Two independent workers answering a job with the same impossible values (what an engine bug
// that the job meets looks like; issue #32: a 3e38 light made every honest worker's tiles +inf,
// and each was quarantined in turn, the job RUNNING for ever): the job fails saying it is the
// job's own, and no worker stays quarantined for it. A worker whose impossible values nobody
// else renders is still quarantined (MalformedRepliesNeverReachTheImage...).
TEST_F(UntrustedWorkersTest, AJobThatTwoWorkersRenderToTheSameImpossibleValuesFailsAndNoWorkerStaysQuarantined) {
  const auto fakes = std::array{fake_worker("first", test::Lie::NaN), fake_worker("second", test::Lie::NaN)};
  test::FakeWorker &first = *fakes[0], &second = *fakes[1];
  ASSERT_FALSE(first.address().empty() || second.address().empty());
  second.hold_after(0);  // until the first has been caught, so that the two answer in turn
  ASSERT_NO_FATAL_FAILURE(start_scheduler({"--batch-ms", "0", "--worker", first.address(), "--worker",
                                           second.address()}));
  const std::string id = submit(job_spec());
  ASSERT_TRUE(watching());
  ASSERT_TRUE(eventually([&] { return quarantined(first.address()); })) << scheduler_->process().output();
  second.release();
  const v1::Job job = finish(id);
  ASSERT_EQ(job.state(), v1::JOB_STATE_FAILED) << scheduler_->process().output();
  EXPECT_NE(job.failure_reason().find("both rendered this job to values no engine should make"), std::string::npos)
      << job.failure_reason();
  EXPECT_NE(job.failure_reason().find("rgba plane"), std::string::npos) << job.failure_reason();
  EXPECT_FALSE(quarantined(second.address())) << scheduler_->process().output();
  // The first is back: listed up (or being probed), not quarantined.
  ASSERT_TRUE(eventually([&] {
    grpc::ClientContext context;
    v1::ListWorkersResponse workers;
    if (!stub_->ListWorkers(&context, v1::ListWorkersRequest(), &workers).ok()) return false;
    for (const v1::WorkerInfo& w : workers.workers()) {
      if (w.state() == v1::WORKER_STATE_QUARANTINED) return false;
    }
    return workers.workers_size() == 2;
  })) << scheduler_->process().output();
}

// A worker's cached scene files are checked before they are used (issue #32: one corrupted on
// disk while the worker was down, and after its restart a job SUCCEEDED with 92% of its pixels
// wrong). The same job again, on the restarted worker whose cached model was damaged in place,
// renders bit-identical to the first time.
TEST_F(UntrustedWorkersTest, ASceneFileDamagedInAWorkersCacheIsNeverRendered) {
  ASSERT_NO_FATAL_FAILURE(start_scheduler({"--float"}));
  const v1::JobSpec spec = job_spec();
  const fs::path cache = dir_ / "cache";
  v1::Job first;
  {
    const auto worker = std::make_unique<test::WorkerProcess>(std::vector<std::string>{
        "--threads", "1", "--cache-dir", cache.string(), "--scheduler", scheduler_->address()});
    ASSERT_TRUE(worker->process().wait_for_line("registered with the scheduler", 30s)) << worker->process().output();
    ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
    ASSERT_TRUE(test::submit(*stub_, spec, first).ok());
    const std::optional<v1::Job> done = test::wait_for_job(*stub_, first.job_id(), final_state, 120s);
    ASSERT_TRUE(done && done->state() == v1::JOB_STATE_SUCCEEDED) << scheduler_->process().output();
    worker->process().send_signal(SIGTERM);
    worker->process().wait_exit(30s);
  }
  // Its laid-out model, damaged in place (the blob it links to with it), while it is down.
  std::vector<fs::path> laid_out;
  for (const auto& e : fs::recursive_directory_iterator(cache)) {
    if (e.path().filename() == "cornell_box.obj" && e.path().string().find("/scenes/") != std::string::npos) {
      laid_out.push_back(e.path());
    }
  }
  ASSERT_EQ(laid_out.size(), 1u) << "the worker laid the scene out under " << cache;
  {
    // The first vertex's sign turned into a 9: "v -1 ..." becomes "v 91 ...", a plausible file
    // of a wrong model.
    const std::string text = test::read_file(laid_out[0]);
    const std::size_t vertex = text.find("\nv -");
    ASSERT_NE(vertex, std::string::npos);
    std::fstream f(laid_out[0], std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(vertex + 3));
    f.put('9');
  }
  const auto restarted = std::make_unique<test::WorkerProcess>(std::vector<std::string>{
      "--threads", "1", "--cache-dir", cache.string(), "--scheduler", scheduler_->address()});
  ASSERT_TRUE(restarted->process().wait_for_line("registered with the scheduler", 30s)) << restarted->process().output();
  v1::Job again;
  ASSERT_TRUE(test::submit(*stub_, spec, again).ok());
  const std::optional<v1::Job> done = test::wait_for_job(*stub_, again.job_id(), final_state, 120s);
  ASSERT_TRUE(done) << scheduler_->process().output();
  ASSERT_EQ(done->state(), v1::JOB_STATE_SUCCEEDED) << done->failure_reason();
  const fs::path a = dir_ / "first.exr", b = dir_ / "again.exr";
  ASSERT_TRUE(test::fetch_result(*stub_, first.job_id(), v1::RESULT_KIND_EXR, a).ok());
  ASSERT_TRUE(test::fetch_result(*stub_, again.job_id(), v1::RESULT_KIND_EXR, b).ok());
  EXPECT_EQ(differing_pixels(read_exr(a), read_exr(b)), 0);
}

// A worker that answers every unit INTERNAL at once (a broken install) beside an honest one: it
// took 3 of 3 jobs down with it, each unit burning its attempts on it in milliseconds (issue
// #32). Now its failures are charged to no unit but its first, it is kept off each job it failed
// three times, it is backed off once it fails several jobs in a row, and all three jobs succeed
// on the honest worker. The honest worker waits until the broken one has been backed off, so
// that the broken one certainly fails two jobs first.
TEST_F(UntrustedWorkersTest, AWorkerThatFailsEveryCallAtOnceFailsNoJobAndIsKeptOffAndBackedOff) {
  const auto fakes = std::array{fake_worker("broken", test::Lie::FailsAtOnce), fake_worker("honest")};
  test::FakeWorker &broken = *fakes[0], &honest = *fakes[1];
  ASSERT_FALSE(broken.address().empty() || honest.address().empty());
  honest.hold_after(0);
  ASSERT_NO_FATAL_FAILURE(start_scheduler({"--float", "--batch-ms", "0", "--worker", broken.address(), "--worker",
                                           honest.address()}));
  ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  std::vector<std::string> ids;
  for (int i = 0; i < 3; ++i) {
    v1::Job job;
    ASSERT_TRUE(test::submit(*stub_, job_spec(), job).ok());
    ids.push_back(job.job_id());
  }
  const auto said = [&](const std::string& text) {
    return scheduler_->process().output().find(text) != std::string::npos;
  };
  ASSERT_TRUE(eventually([&] { return said("worker " + broken.address() + " is backed off"); }))
      << scheduler_->process().output();
  EXPECT_TRUE(said("job " + ids[0] + ": worker " + broken.address() + " is kept off it from now on"))
      << scheduler_->process().output();
  honest.release();

  for (const std::string& id : ids) {
    const std::optional<v1::Job> job = test::wait_for_job(*stub_, id, final_state, 180s);
    ASSERT_TRUE(job) << scheduler_->process().output();
    EXPECT_EQ(job->state(), v1::JOB_STATE_SUCCEEDED) << job->failure_reason() << "\n" << scheduler_->process().output();
  }
  // Its failures said why even though it said nothing, and it was never quarantined: a broken
  // worker is no liar.
  EXPECT_TRUE(said("INTERNAL: (it gave no reason)")) << scheduler_->process().output();
  EXPECT_FALSE(quarantined(broken.address()));
  // Backed off, its calls stayed few: three a job at most, and those of its two slots.
  EXPECT_GT(broken.lies_told(), 0);
  EXPECT_LE(broken.lies_told(), 3 * 3 + 2);
  // farm workers lists the job it is kept off.
  grpc::ClientContext context;
  v1::ListWorkersResponse workers;
  ASSERT_TRUE(stub_->ListWorkers(&context, v1::ListWorkersRequest(), &workers).ok());
  bool listed = false;
  for (const v1::WorkerInfo& w : workers.workers()) {
    if (w.address() != broken.address()) continue;
    listed = std::find(w.blocked_jobs().begin(), w.blocked_jobs().end(), ids[0]) != w.blocked_jobs().end();
  }
  EXPECT_TRUE(listed) << workers.DebugString();
}

// RegisterWorker from fresh addresses (which never answer) and again and again from one that
// does: the scheduler's threads and memory do not grow with the number of calls.
TEST_F(UntrustedWorkersTest, AThousandRegistrationsLeaveThreadsAndMemoryFlat) {
  test::FakeWorker same(dir_ / "same");
  ASSERT_FALSE(same.address().empty());
  ASSERT_NO_FATAL_FAILURE(start_scheduler({}));
  const pid_t pid = scheduler_->process().pid();
  int calls = 0;
  const auto register_some = [&](int n) {
    for (int i = 0; i < n; ++i, ++calls) {
      v1::RegisterWorkerRequest request;
      // Odd calls: the same worker registering again; even calls: a worker never seen before, at
      // a loopback address where nothing listens (port 9 of 127.0.x.y).
      request.set_address(calls % 2 ? same.address()
                                    : fmt::format("127.0.{}.{}:9", 1 + calls / 250, 1 + calls % 250));
      request.set_threads(1);
      v1::RegisterWorkerResponse response;
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + 30s);
      const grpc::Status status = stub_->RegisterWorker(&context, request, &response);
      ASSERT_TRUE(status.ok()) << status.error_message();
    }
  };
  const test::ProcStatus start = test::proc_status(pid);
  ASSERT_NO_FATAL_FAILURE(register_some(100));  // gRPC and the allocator warm up
  const test::ProcStatus warm = test::proc_status(pid);
  ASSERT_NO_FATAL_FAILURE(register_some(1000));
  const test::ProcStatus end = test::proc_status(pid);
  std::printf("scheduler threads %ld -> %ld (after 100 calls) -> %ld (after 1000 more); "
              "VmSize %ld -> %ld -> %ld MiB; VmRSS %ld -> %ld -> %ld MiB\n",
              start.threads, warm.threads, end.threads, start.vm_size_kb / 1024, warm.vm_size_kb / 1024,
              end.vm_size_kb / 1024, start.vm_rss_kb / 1024, warm.vm_rss_kb / 1024, end.vm_rss_kb / 1024);
  ASSERT_GT(warm.threads, 0);
  // Bounds with room for gRPC's own pools, far below what one leaked thread a call would give.
  EXPECT_LE(end.threads, warm.threads + 16);
  EXPECT_LT(end.vm_size_kb - warm.vm_size_kb, 512 * 1024);
  EXPECT_LT(end.vm_rss_kb - warm.vm_rss_kb, 64 * 1024);
}

// The flag is documented where users look, and a fraction outside [0, 1] is bad input.
TEST(FarmSchedulerVerifyFraction, IsInTheHelpAndOutOfRangeValuesAreRefused) {
  const test::CommandResult help = test::run_command(test::farm_command("scheduler --help"));
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("--verify-fraction"), std::string::npos) << help.output;
  const test::CommandResult bad = test::run_command(test::farm_command("scheduler --data-dir /nonexistent --verify-fraction 1.5"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--verify-fraction"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace farm
