// Starts the real `farm worker` binary and calls it through the generated farm.v1.Worker stub:
// tiles must come back bit-identical to render_tile in this process, bad input must be answered
// with the right status without hurting the worker, and deadlines and signals must be honoured.
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <fstream>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/engine.h"
#include "renderer/job/job.h"
#include "renderer/job/job_limits.h"
#include "renderer/job/scene_builder.h"
#include "server/common/asset_store.h"
#include "server/common/health_check.h"
#include "server/common/scene_hash.h"
#include "server/common/sha256.h"
#include "server/common/tile_codec.h"
#include "tests/support/background_process.h"
#include "tests/support/fake_scheduler.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::kSource;

std::unique_ptr<v1::Worker::Stub> worker_stub(const std::string& address) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  return v1::Worker::NewStub(
      grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args));
}

v1::RenderTileRequest tile_request(const v1::JobSpec& spec, const Rect& r) {
  v1::RenderTileRequest request;
  *request.mutable_job() = spec;
  request.set_scene_hash(scene_hash(spec));
  request.mutable_rect()->set_x0(r.x0);
  request.mutable_rect()->set_y0(r.y0);
  request.mutable_rect()->set_x1(r.x1);
  request.mutable_rect()->set_y1(r.y1);
  return request;
}

grpc::Status render(v1::Worker::Stub& stub, const v1::RenderTileRequest& request,
                    v1::RenderTileResponse& response, std::chrono::milliseconds timeout = 120s) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + timeout);
  return stub.RenderTile(&context, request, &response);
}

// The same rect rendered here, from the job as the project ships it (jobs/ is its folder).
v1::TileData render_in_process(const v1::JobSpec& spec, const Rect& rect) {
  const Job job = parse_job(spec.job_json(), kSource / "jobs" / spec.file_name());
  const PreparedScene scene(build_scene(job));
  TileBuffer tile;
  render_tile(scene, job.render, rect, tile);
  v1::TileData data;
  encode_tile(tile, data);
  return data;
}

void expect_bit_identical(const v1::TileData& got, const v1::TileData& want, const std::string& what) {
  EXPECT_EQ(got.width(), want.width()) << what;
  EXPECT_EQ(got.height(), want.height()) << what;
  EXPECT_TRUE(got.rgba() == want.rgba()) << what << ": rgba differs";
  EXPECT_TRUE(got.depth() == want.depth()) << what << ": depth differs";
  EXPECT_TRUE(got.normal() == want.normal()) << what << ": normal differs";
  EXPECT_TRUE(got.albedo() == want.albedo()) << what << ": albedo differs";
  EXPECT_TRUE(got.bvh_cost() == want.bvh_cost()) << what << ": bvh_cost differs";
  EXPECT_TRUE(got.variance() == want.variance()) << what << ": variance differs";
}

class FarmWorkerTest : public ::testing::Test {
 protected:
  // A worker fetching assets from a fake scheduler that has the Cornell box's files.
  std::unique_ptr<test::WorkerProcess> start_worker_with_scheduler(int threads = 2,
                                                                   const std::string& log_level = "info") {
    for (const auto& [path, file] : test::cornell_assets()) scheduler_.add_asset(test::read_file(file));
    auto worker = std::make_unique<test::WorkerProcess>(std::vector<std::string>{
        "--threads", std::to_string(threads), "--scheduler", scheduler_.address(), "--cache-dir",
        (dir_ / "cache").string(), "--log-level", log_level});
    EXPECT_FALSE(worker->address().empty()) << worker->process().output();
    return worker;
  }

  test::TempDir dir_;
  test::FakeScheduler scheduler_;
};

TEST_F(FarmWorkerTest, RenderTileIsBitIdenticalToInProcessRenderTileForEveryEngine) {
  auto worker = start_worker_with_scheduler();
  ASSERT_FALSE(worker->address().empty());
  auto stub = worker_stub(worker->address());
  const Rect rect{5, 3, 45, 37};  // crosses sub-tile boundaries; not aligned to anything
  for (const std::string engine : {"raster", "whitted", "path"}) {
    const v1::JobSpec spec = test::cornell_job_spec(engine, 48, 40, engine == "path" ? 4 : 1);
    v1::RenderTileResponse response;
    const grpc::Status status = render(*stub, tile_request(spec, rect), response);
    ASSERT_TRUE(status.ok()) << engine << ": " << status.error_message() << "\n"
                             << worker->process().output();
    EXPECT_EQ(response.tile().rect().x0(), 5);
    EXPECT_EQ(response.tile().rect().y1(), 37);
    EXPECT_FALSE(response.tile().depth().empty());  // the job asks for depth, normal, albedo, variance
    EXPECT_FALSE(response.tile().variance().empty());
    expect_bit_identical(response.tile(), render_in_process(spec, rect), engine);
    // Not trivially equal: the middle of the box is covered and lit.
    const TileBuffer tile = decode_tile(response.tile());
    EXPECT_EQ(tile.rgba(24, 20).w, 1.0f) << engine;
    EXPECT_GT(tile.rgba(24, 20).x, 0.0f) << engine;
    EXPECT_FALSE(response.stats().scene_cache_hit());
    if (engine == "raster") {
      EXPECT_GT(response.stats().fragments(), 0u);
    }
    if (engine == "path") {
      EXPECT_EQ(response.stats().samples(), 40u * 34u * 4u);
    }
    // The render threads' CPU time: some, and no more than all its threads busy all along.
    EXPECT_GT(response.stats().cpu_ms(), 0.0) << engine;
    EXPECT_LE(response.stats().cpu_ms(), response.stats().render_ms() * response.stats().threads() + 1.0) << engine;

    // The second tile of the same job reuses the prepared scene.
    v1::RenderTileResponse again;
    ASSERT_TRUE(render(*stub, tile_request(spec, {0, 0, 48, 40}), again).ok());
    EXPECT_TRUE(again.stats().scene_cache_hit());
    expect_bit_identical(again.tile(), render_in_process(spec, {0, 0, 48, 40}), engine + " full");
  }
  // Each blob was fetched once, though three jobs use it.
  EXPECT_EQ(scheduler_.get_asset_calls(), 2);
}

TEST_F(FarmWorkerTest, ConcurrentTilesOfOneJobMatchInProcess) {
  auto worker = start_worker_with_scheduler();
  ASSERT_FALSE(worker->address().empty());
  auto stub = worker_stub(worker->address());
  const v1::JobSpec spec = test::cornell_job_spec("path", 40, 40, 2);
  const std::vector<Rect> quads{{0, 0, 20, 20}, {20, 0, 40, 20}, {0, 20, 20, 40}, {20, 20, 40, 40}};
  std::vector<std::future<std::pair<grpc::Status, v1::RenderTileResponse>>> calls;
  for (const Rect& q : quads) {
    calls.push_back(std::async(std::launch::async, [&, q] {
      v1::RenderTileResponse response;
      grpc::Status status = render(*stub, tile_request(spec, q), response);
      return std::make_pair(status, response);
    }));
  }
  int prepared = 0;
  for (std::size_t i = 0; i < quads.size(); ++i) {
    auto [status, response] = calls[i].get();
    ASSERT_TRUE(status.ok()) << status.error_message();
    expect_bit_identical(response.tile(), render_in_process(spec, quads[i]), "quad " + std::to_string(i));
    prepared += response.stats().scene_cache_hit() ? 0 : 1;
  }
  EXPECT_EQ(prepared, 1);  // one call prepared the scene, the others waited for it
}

TEST_F(FarmWorkerTest, MalformedJobIsInvalidArgumentAndTheWorkerKeepsServing) {
  auto worker = start_worker_with_scheduler();
  ASSERT_FALSE(worker->address().empty());
  auto stub = worker_stub(worker->address());

  v1::JobSpec broken = test::cornell_job_spec("raster", 16, 16, 1);
  broken.set_job_json("{ \"version\": 1, \"scene\": ");
  v1::RenderTileResponse response;
  grpc::Status status = render(*stub, tile_request(broken, {0, 0, 8, 8}), response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find("cornell.json"), std::string::npos) << status.error_message();

  v1::JobSpec bad_width = test::cornell_job_spec("raster", 16, 16, 1);
  bad_width.set_job_json(R"({"version": 1, "scene": {"objects": [{"file": "assets/cornell_box.obj"}]},
                             "render": {"width": -5}})");
  status = render(*stub, tile_request(bad_width, {0, 0, 8, 8}), response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("cornell.json: render.width"), std::string::npos)
      << status.error_message();

  v1::JobSpec escaping = test::cornell_job_spec("raster", 16, 16, 1);
  escaping.mutable_assets(1)->set_path("../cornell_box.mtl");
  status = render(*stub, tile_request(escaping, {0, 0, 8, 8}), response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();

  const v1::JobSpec good = test::cornell_job_spec("raster", 16, 16, 1);
  status = render(*stub, tile_request(good, {0, 0, 100, 100}), response);  // clipped to the image
  ASSERT_TRUE(status.ok()) << status.error_message();
  expect_bit_identical(response.tile(), render_in_process(good, {0, 0, 16, 16}), "after errors");

  status = render(*stub, tile_request(good, {16, 0, 20, 8}), response);  // nothing left after clipping
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  v1::RenderTileRequest wrong_hash = tile_request(good, {0, 0, 8, 8});
  wrong_hash.set_scene_hash(std::string(64, '0'));
  EXPECT_EQ(render(*stub, wrong_hash, response).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

// `request` with the Cornell box's files inline, as a scheduler sends them to a worker that
// cannot fetch.
v1::RenderTileRequest with_cornell_files_inline(v1::RenderTileRequest request) {
  for (const auto& [path, file] : test::cornell_assets()) {
    v1::InlineAsset& asset = *request.add_assets();
    asset.set_data(test::read_file(file));
    asset.set_sha256(sha256_hex(asset.data()));
  }
  return request;
}

// What a scheduler sends a worker it cannot expect to fetch: the files inline, verified by hash.
TEST_F(FarmWorkerTest, InlineAssetsAreVerifiedAndKept) {
  const fs::path cache = dir_ / "cache";
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", cache.string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  auto stub = worker_stub(worker.address());
  const v1::JobSpec spec = test::cornell_job_spec("raster", 16, 16, 1);
  v1::RenderTileRequest request = with_cornell_files_inline(tile_request(spec, {0, 0, 16, 16}));
  v1::RenderTileRequest lying = request;
  lying.mutable_assets(0)->mutable_data()->append(" ");  // bytes that do not match their hash
  v1::RenderTileResponse response;
  grpc::Status status = render(*stub, lying, response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();

  status = render(*stub, request, response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  expect_bit_identical(response.tile(), render_in_process(spec, {0, 0, 16, 16}), "inline assets");
  // Kept: the next call needs no files.
  status = render(*stub, tile_request(spec, {0, 0, 8, 8}), response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_TRUE(AssetStore(cache / "blobs").has(request.assets(0).sha256()));
}

// A worker keeps the files sent with a call: one the job does not list would only fill its disk
// (at an older HEAD a 100 MB blob no job uses was kept). The call is refused naming the hash, and
// nothing of it is kept, not even the files the job does list.
TEST_F(FarmWorkerTest, InlineAssetTheJobDoesNotListIsRefusedAndNothingIsKept) {
  const fs::path cache = dir_ / "cache";
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", cache.string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  auto stub = worker_stub(worker.address());
  const v1::JobSpec spec = test::cornell_job_spec("raster", 16, 16, 1);
  v1::RenderTileRequest request = with_cornell_files_inline(tile_request(spec, {0, 0, 16, 16}));
  v1::RenderTileRequest stuffed = request;
  v1::InlineAsset& unused = *stuffed.add_assets();
  unused.set_data(std::string(4 << 20, 'u'));
  unused.set_sha256(sha256_hex(unused.data()));
  v1::RenderTileResponse response;
  const grpc::Status status = render(*stub, stuffed, response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find(unused.sha256()), std::string::npos) << status.error_message();
  const AssetStore blobs(cache / "blobs");
  for (const v1::InlineAsset& asset : stuffed.assets()) EXPECT_FALSE(blobs.has(asset.sha256()));

  // The same call with only the job's files renders.
  ASSERT_TRUE(render(*stub, request, response).ok());
  EXPECT_FALSE(blobs.has(unused.sha256()));
}

// The scheduler sends a job's text once per worker: later calls name only the scene hash. A
// worker renders those from the scene it prepared, and answers NOT_FOUND for one it does not hold.
TEST_F(FarmWorkerTest, ACallWithoutItsJobRendersThePreparedSceneOrIsNotFound) {
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", (dir_ / "cache").string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  auto stub = worker_stub(worker.address());
  const v1::JobSpec spec = test::cornell_job_spec("whitted", 32, 32, 1);
  const v1::RenderTileRequest with_job = with_cornell_files_inline(tile_request(spec, {0, 0, 32, 32}));
  v1::RenderTileRequest without_job;
  without_job.set_scene_hash(scene_hash(spec));
  *without_job.mutable_rect() = with_job.rect();

  v1::RenderTileResponse response;
  grpc::Status status = render(*stub, without_job, response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
  EXPECT_NE(status.error_message().find("send its job"), std::string::npos) << status.error_message();

  ASSERT_TRUE(render(*stub, with_job, response).ok());
  status = render(*stub, without_job, response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  expect_bit_identical(response.tile(), render_in_process(spec, {0, 0, 32, 32}), "without its job");

  v1::RenderTileRequest bad = without_job;
  bad.set_scene_hash("not-a-hash");
  EXPECT_EQ(render(*stub, bad, response).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  bad = without_job;
  *bad.add_assets() = with_job.assets(0);  // files come only with the job that lists them
  EXPECT_EQ(render(*stub, bad, response).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(FarmWorkerTest, MissingAssetsWithoutSchedulerAreFailedPreconditionUntilCached) {
  const fs::path cache = dir_ / "cache";
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", cache.string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  auto stub = worker_stub(worker.address());
  const v1::JobSpec spec = test::cornell_job_spec("raster", 16, 16, 1);
  v1::RenderTileResponse response;
  grpc::Status status = render(*stub, tile_request(spec, {0, 0, 16, 16}), response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("assets/cornell_box.obj"), std::string::npos)
      << status.error_message();

  // Blobs placed in the worker's cache (as a shared cache or an earlier fetch would) are used.
  const AssetStore store(cache / "blobs");
  for (const auto& [path, file] : test::cornell_assets()) store.add(test::read_file(file));
  status = render(*stub, tile_request(spec, {0, 0, 16, 16}), response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  expect_bit_identical(response.tile(), render_in_process(spec, {0, 0, 16, 16}), "from cache");
}

TEST_F(FarmWorkerTest, HealthCheckReportsServing) {
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", (dir_ / "cache").string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  const HealthCheck health = check_health(
      grpc::CreateChannel(worker.address(), grpc::InsecureChannelCredentials()),
      std::chrono::system_clock::now() + 30s);
  ASSERT_TRUE(health.status.ok()) << health.status.error_message();
  EXPECT_EQ(health.serving_status, 1);  // SERVING
  EXPECT_TRUE(health.serving());
}

TEST_F(FarmWorkerTest, ReflectionListsTheWorkerService) {
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", (dir_ / "cache").string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  // What `grpcurl list` sends: ServerReflectionRequest{list_services: ""} (field 7, empty string:
  // bytes 3a 00); the reply lists the service names as strings.
  auto channel = grpc::CreateChannel(worker.address(), grpc::InsecureChannelCredentials());
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 30s);
  grpc::CompletionQueue cq;
  const auto step = [&cq] {
    void* tag = nullptr;
    bool ok = false;
    return cq.Next(&tag, &ok) && ok;
  };
  auto call = stub.PrepareCall(
      &context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &cq);
  call->StartCall(nullptr);
  ASSERT_TRUE(step());
  grpc::Slice list_services(std::string("\x3a\x00", 2));
  const grpc::ByteBuffer request(&list_services, 1);
  call->Write(request, nullptr);
  ASSERT_TRUE(step());
  call->WritesDone(nullptr);
  ASSERT_TRUE(step());
  grpc::ByteBuffer reply;
  call->Read(&reply, nullptr);
  ASSERT_TRUE(step());
  grpc::Status status;
  call->Finish(&status, nullptr);
  ASSERT_TRUE(step());
  EXPECT_TRUE(status.ok()) << status.error_message();
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(reply.Dump(&slices).ok());
  std::string bytes;
  for (const grpc::Slice& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  EXPECT_NE(bytes.find("farm.v1.Worker"), std::string::npos);
  EXPECT_NE(bytes.find("grpc.health.v1.Health"), std::string::npos);
  cq.Shutdown();
  while (step()) {
  }
}

TEST_F(FarmWorkerTest, DeadlineStopsTheRenderAndTheWorkerStaysResponsive) {
  auto worker = start_worker_with_scheduler();
  ASSERT_FALSE(worker->address().empty());
  auto stub = worker_stub(worker->address());
  // Warm the scene first, so the deadline falls in the middle of rendering.
  const v1::JobSpec slow = test::cornell_job_spec("path", 256, 256, 4096);
  v1::RenderTileResponse response;
  ASSERT_TRUE(render(*stub, tile_request(slow, {0, 0, 1, 1}), response, 60s).ok());

  const auto start = std::chrono::steady_clock::now();
  const grpc::Status status = render(*stub, tile_request(slow, {0, 0, 256, 256}), response, 500ms);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  // The abandoned tile's queued sub-tiles are skipped: a small tile right after comes back soon
  // (the whole 256x256 at 4096 spp would take minutes).
  const v1::JobSpec quick = test::cornell_job_spec("raster", 16, 16, 1);
  const grpc::Status after = render(*stub, tile_request(quick, {0, 0, 16, 16}), response, 60s);
  EXPECT_TRUE(after.ok()) << after.error_message();
  EXPECT_LT(std::chrono::steady_clock::now() - start, 30s);
}

// Tiles no worker finishes in a test's lifetime, one per engine: the most samples a job may ask
// for (2^20 a pixel; raster and whitted supersample), over rects that make hours of work even
// for the cheap rasterizer.
struct HugeTile {
  const char* engine;
  int size;
};
constexpr HugeTile kHugeTiles[] = {{"raster", 256}, {"whitted", 64}, {"path", 16}};

v1::JobSpec huge_spec(const HugeTile& t) { return test::cornell_job_spec(t.engine, t.size, t.size, kMaxSpp); }

// Prepares the scene of `spec` on the worker, so that a call after it starts rendering at once.
// The call itself is cut short by its deadline (the scene is prepared and cached all the same);
// the worker's log line says when the scene is ready.
void prepare_scene(v1::Worker::Stub& stub, test::WorkerProcess& worker, const v1::JobSpec& spec) {
  v1::RenderTileResponse response;
  render(stub, tile_request(spec, {0, 0, 1, 1}), response, 200ms);
  EXPECT_TRUE(worker.process().wait_for_line("scene " + scene_hash(spec).substr(0, 12), 60s))
      << worker.process().output();
}

// One RenderTile call on a thread of its own, cancellable from the test.
class CallInFlight {
 public:
  CallInFlight(v1::Worker::Stub& stub, const v1::RenderTileRequest& request) {
    context_.set_deadline(std::chrono::system_clock::now() + 600s);
    thread_ = std::thread([this, &stub, request] {
      v1::RenderTileResponse response;
      status_ = stub.RenderTile(&context_, request, &response);
    });
  }
  ~CallInFlight() { finish(); }
  void cancel() { context_.TryCancel(); }
  grpc::Status finish() {
    if (thread_.joinable()) thread_.join();
    return status_;
  }

 private:
  grpc::ClientContext context_;
  grpc::Status status_;
  std::thread thread_;
};

// A small call right after a stopped one succeeds: the stopped render no longer holds the
// worker's one render thread. `busy` says what it means when it does not.
void expect_next_call_served(v1::Worker::Stub& stub, test::WorkerProcess& worker, const std::string& busy) {
  const v1::JobSpec quick = test::cornell_job_spec("raster", 16, 16, 1);
  v1::RenderTileResponse response;
  const grpc::Status next = render(stub, tile_request(quick, {0, 0, 16, 16}), response, 30s);
  EXPECT_TRUE(next.ok()) << busy << ": " << next.error_message() << "\n" << worker.process().output();
}

// The worker has one render thread: were a stopped render still running on it, the small call
// after it would wait behind hours of work.
TEST_F(FarmWorkerTest, HugeSppStopsAtTheDeadlineForEveryEngineAndTheWorkerServesTheNextCall) {
  auto worker = start_worker_with_scheduler(1);
  ASSERT_FALSE(worker->address().empty());
  auto stub = worker_stub(worker->address());
  for (const HugeTile& huge : kHugeTiles) {
    const v1::JobSpec spec = huge_spec(huge);
    prepare_scene(*stub, *worker, spec);
    v1::RenderTileResponse response;
    const grpc::Status late = render(*stub, tile_request(spec, {0, 0, huge.size, huge.size}), response, 1s);
    EXPECT_EQ(late.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << huge.engine << ": " << late.error_message();
    expect_next_call_served(*stub, *worker, std::string(huge.engine) + ": the worker is still busy with the late tile");
  }
}

TEST_F(FarmWorkerTest, HugeSppCancelledMidTileFreesTheWorkerForEveryEngine) {
  auto worker = start_worker_with_scheduler(1);
  ASSERT_FALSE(worker->address().empty());
  auto stub = worker_stub(worker->address());
  for (const HugeTile& huge : kHugeTiles) {
    const v1::JobSpec spec = huge_spec(huge);
    prepare_scene(*stub, *worker, spec);
    CallInFlight call(*stub, tile_request(spec, {0, 0, huge.size, huge.size}));
    std::this_thread::sleep_for(500ms);  // into the render (an earlier cancel proves less, never fails)
    call.cancel();
    EXPECT_EQ(call.finish().error_code(), grpc::StatusCode::CANCELLED) << huge.engine;
    expect_next_call_served(*stub, *worker, std::string(huge.engine) + ": the worker is still busy with the cancelled tile");
  }
}

// A raster frame whose set-up (binning) is about the largest one allowed: 128 quads that each
// cover nearly all of a 16384x16384 image (and stay inside it, so that clipping splits none),
// 63 million triangle-in-bin entries to file before any pixel.
v1::JobSpec huge_setup_spec(const fs::path& dir) {
  const fs::path obj = dir / "quads.obj";
  {
    std::ofstream out(obj);
    for (int i = 0; i < 128; ++i) {
      const double z = -0.001 * i;
      out << "v -2 -2 " << z << "\nv 2 -2 " << z << "\nv 2 2 " << z << "\nv -2 2 " << z << "\n";
      out << "f " << 4 * i + 1 << ' ' << 4 * i + 2 << ' ' << 4 * i + 3 << ' ' << 4 * i + 4 << "\n";
    }
  }
  const std::string json = R"({"version": 1, "name": "quads",
    "scene": {"objects": [{"file": "quads.obj"}], "camera": {"position": [0, 0, 5], "target": [0, 0, 0]}},
    "render": {"engine": "raster", "width": 16384, "height": 16384, "spp": 4},
    "output": {"image": "out/quads.exr"}})";
  return test::make_job_spec(json, {{"quads.obj", obj}});
}

// A stop that arrives while the frame is being set up stops the set-up itself (the worker logs
// it from the set-up's own thread), and the worker's one render thread serves the next call.
// The set-up of this frame takes 250 ms on one thread of a 2-core VM with its memory warm (1 s
// cold): the cancel comes 100 ms into the first call (which also fetches and loads the scene,
// about 20 ms), and the second call, whose scene is then cached and whose set-up starts at once,
// has a deadline of 150 ms.
TEST_F(FarmWorkerTest, ADeadlineOrACancelDuringTheFramesSetUpStopsItAndFreesTheWorker) {
  const v1::JobSpec spec = huge_setup_spec(dir_.path());
  for (const v1::AssetRef& ref : spec.assets()) scheduler_.add_asset(test::read_file(dir_ / ref.path()));
  auto worker = start_worker_with_scheduler(1, "debug");
  ASSERT_FALSE(worker->address().empty());
  auto stub = worker_stub(worker->address());
  {
    v1::RenderTileRequest request = tile_request(spec, {0, 0, 16, 16});
    request.set_job_id("cancelled-setup");
    CallInFlight call(*stub, request);
    std::this_thread::sleep_for(100ms);  // into the set-up (an earlier cancel proves less)
    call.cancel();
    EXPECT_EQ(call.finish().error_code(), grpc::StatusCode::CANCELLED);
    EXPECT_TRUE(worker->process().wait_for_line("job cancelled-setup: the frame's set-up stopped", 30s))
        << worker->process().output();
    expect_next_call_served(*stub, *worker, "the worker is still busy with the cancelled set-up");
  }
  {
    v1::RenderTileRequest request = tile_request(spec, {0, 0, 16, 16});
    request.set_job_id("late-setup");
    v1::RenderTileResponse response;
    EXPECT_EQ(render(*stub, request, response, 150ms).error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
    EXPECT_TRUE(worker->process().wait_for_line("job late-setup: the frame's set-up stopped", 30s))
        << worker->process().output();
    expect_next_call_served(*stub, *worker, "the worker is still busy with the late set-up");
  }
}

// SIGTERM in the middle of hours of rendering: the call is cancelled after the grace period, the
// render stops, and the worker exits 0 (it used to render on, deaf to SIGTERM, until kill -9).
TEST_F(FarmWorkerTest, SigtermWhileRenderingHugeSppExitsWithCode0) {
  auto worker = start_worker_with_scheduler(1);
  ASSERT_FALSE(worker->address().empty());
  auto stub = worker_stub(worker->address());
  const v1::JobSpec spec = huge_spec({"path", 16});
  prepare_scene(*stub, *worker, spec);
  CallInFlight call(*stub, tile_request(spec, {0, 0, 16, 16}));
  std::this_thread::sleep_for(500ms);
  worker->process().send_signal(SIGTERM);
  // The bound is generous for a loaded machine; the worker takes about 1.5 s (README).
  const std::optional<int> code = worker->process().wait_exit(15s);
  ASSERT_TRUE(code.has_value()) << "worker still running after SIGTERM\n" << worker->process().output();
  EXPECT_EQ(*code, 0) << worker->process().output();
  const grpc::Status status = call.finish();
  EXPECT_FALSE(status.ok()) << "a render of hours cannot have finished";
}

TEST_F(FarmWorkerTest, SigtermShutsTheWorkerDownCleanly) {
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", (dir_ / "cache").string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  worker.process().send_signal(SIGTERM);
  const std::optional<int> code = worker.process().wait_exit(20s);
  ASSERT_TRUE(code.has_value()) << "worker still running after SIGTERM";
  EXPECT_EQ(*code, 0) << worker.process().output();
}

class FarmWorkerCliTest : public test::FarmCliFixture {};

TEST_F(FarmWorkerCliTest, HelpExplainsTheOptions) {
  const auto r = test::run_command(farm("worker --help"));
  EXPECT_EQ(r.exit_code, 0);
  for (const char* option : {"--listen", "--threads", "--scheduler", "--cache-dir", "--max-scenes",
                             "--cache-memory"}) {
    EXPECT_NE(r.output.find(option), std::string::npos) << option << "\n" << r.output;
  }
}

TEST_F(FarmWorkerCliTest, UnusableListenAddressExitsWith2) {
  const auto r = test::run_command(farm("worker --insecure --listen 256.1.1.1:99999 --cache-dir " +
                                        test::shell_quote((dir_ / "c").string())));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cannot listen"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace farm
