// The embedded farm (scheduler core + in-process worker, no sockets) renders a job to the same
// pixels as render_frame, and the job merger pastes tile files back bit-exactly.
#include "server/embedded/embedded_farm.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <atomic>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>

#include "renderer/accel/prepared_scene.h"
#include "renderer/engine.h"
#include "renderer/image/exr_io.h"
#include "renderer/image/pass_merge.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "server/common/tile_codec.h"
#include "server/embedded/in_process_tile_worker.h"
#include "server/scheduler/jobs/frame_assembly.h"
#include "server/scheduler/jobs/job_merger.h"
#include "server/scheduler/scheduler_core.h"
#include "server/scheduler/store/job_store.h"
#include "tests/support/eventually.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/in_process_worker.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TileBuffer render_locally(const v1::JobSpec& spec) {
  const Job job = parse_job(spec.job_json(), test::kSource / "jobs" / spec.file_name());
  const PreparedScene scene(build_scene(job));
  return render_frame(scene, job.render);
}

// Every channel of every pixel, compared as bits.
void expect_same_pixels(const TileBuffer& a, const TileBuffer& b, const std::string& what) {
  ASSERT_EQ(a.rect(), b.rect()) << what;
  int differing = 0;
  for (int y = a.rect().y0; y < a.rect().y1; ++y) {
    for (int x = a.rect().x0; x < a.rect().x1; ++x) {
      if (std::memcmp(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)) != 0) ++differing;
      if (a.aovs().has(Aov::Depth) && !same_bits(a.depth(x, y), b.depth(x, y))) ++differing;
      if (a.aovs().has(Aov::Normal) &&
          std::memcmp(&a.normal(x, y), &b.normal(x, y), sizeof(glm::vec3)) != 0) ++differing;
      if (a.aovs().has(Aov::Albedo) &&
          std::memcmp(&a.albedo(x, y), &b.albedo(x, y), sizeof(glm::vec3)) != 0) ++differing;
      if (a.aovs().has(Aov::Variance) &&
          std::memcmp(&a.variance(x, y), &b.variance(x, y), sizeof(glm::vec3)) != 0) ++differing;
    }
  }
  EXPECT_EQ(differing, 0) << what;
}

// `farm render`'s farm makes units of at least 256 pixels a side out of the job's 32 px tiles
// (unit_grid.h): a 640x300 frame is 3 x 2 units, not 20 x 10, and its pixels are render_frame's
// whichever way it was cut, the units going out in batches of whole rows.
// The farm compresses merged frames on the threads it renders on (`farm render --threads N`
// uses N cores, not every core for its files); 0 stays all cores.
TEST(EmbeddedFarmTest, ItsMergesUseItsThreads) {
  for (int threads : {1, 3, 0}) {
    EmbeddedFarmOptions options;
    options.threads = threads;
    EmbeddedFarm farm(options);
    EXPECT_EQ(farm.core().options().merge_threads, threads);
  }
}

TEST(EmbeddedFarmTest, ItsUnitsAreGroupsOfTheJobsTilesAndThePixelsDoNotChange) {
  test::TempDir dir;
  for (const int min_unit_edge : {256, 0}) {
    EmbeddedFarmOptions options;
    options.data_dir = dir / ("farm" + std::to_string(min_unit_edge));
    options.threads = 2;
    options.exr_type = ExrPixelType::Float;
    options.min_unit_edge = min_unit_edge;
    EmbeddedFarm farm(options);
    for (const auto& [path, file] : test::cornell_assets()) farm.add_asset_file(file);
    for (const std::string engine : {"raster", "path"}) {
      const v1::JobSpec spec = test::cornell_job_spec(engine, 640, 300, 2);
      const EmbeddedResult result = farm.run(spec);
      ASSERT_EQ(result.job.state(), v1::JOB_STATE_SUCCEEDED) << result.job.failure_reason();
      EXPECT_EQ(result.job.tiles_total() / result.job.passes(), min_unit_edge == 256 ? 6u : 200u) << engine;
      expect_same_pixels(read_exr(result.exr), render_locally(spec), engine + " with units of " +
                                                                          std::to_string(min_unit_edge));
    }
  }
}

TEST(EmbeddedFarmTest, CornellThroughTheEmbeddedFarmIsBitIdenticalToRenderFrame) {
  test::TempDir dir;
  EmbeddedFarmOptions options;
  options.data_dir = dir / "farm";
  options.threads = 2;
  options.exr_type = ExrPixelType::Float;
  EmbeddedFarm farm(options);
  for (const auto& [path, file] : test::cornell_assets()) farm.add_asset_file(file);
  for (const std::string engine : {"raster", "whitted", "path"}) {
    const v1::JobSpec spec = test::cornell_job_spec(engine, 64, 48, engine == "path" ? 4 : 1);
    // The job's every event reaches `progress`, however fast it renders: the last one is final
    // and counts every tile, and tiles_done never goes back.
    int progress_calls = 0;
    v1::Job last;
    bool monotonic = true;
    const EmbeddedResult result = farm.run(spec, [&](const v1::Job& j) {
      if (progress_calls++ > 0 && j.tiles_done() < last.tiles_done()) monotonic = false;
      last = j;
    });
    ASSERT_EQ(result.job.state(), v1::JOB_STATE_SUCCEEDED) << result.job.failure_reason();
    EXPECT_EQ(result.job.tiles_done(), result.job.tiles_total());
    EXPECT_EQ(result.job.tiles_rendered(), result.job.tiles_total());
    EXPECT_GT(progress_calls, 0);
    EXPECT_EQ(last.state(), v1::JOB_STATE_SUCCEEDED) << engine;
    EXPECT_EQ(last.tiles_done(), result.job.tiles_total()) << engine;
    EXPECT_TRUE(monotonic) << engine;
    // The scene submit built to validate the job is the one rendered: no call prepared it again.
    EXPECT_EQ(result.job.stats().prepare_ms(), 0.0);
    EXPECT_TRUE(std::filesystem::exists(result.preview));
    const TileBuffer local = render_locally(spec);
    expect_same_pixels(read_exr(result.exr), local, engine);
    if (engine == "path") {
      EXPECT_EQ(result.job.stats().samples(), 64u * 48u * 4u);
    }
    if (engine != "raster") {
      EXPECT_EQ(result.job.stats().rays(), local.stats().rays) << engine;
    }
  }
}

// Tiles that take a fraction of a millisecond go out in batches (a row's run, or whole rows) once
// the first are timed; with batch_target 0, one tile a call. Units of one tile each here
// (min_unit_edge 0). The job store's `part` of each tile says which call rendered it; pixels are
// the same bits either way.
TEST(EmbeddedFarmTest, CheapTilesGoOutInRowBatchesAndThePixelsStayTheSame) {
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("path", 96, 64, 2));
  job["render"]["tile_size"] = 8;  // a grid of 12 x 8 tiles
  const v1::JobSpec spec = test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json");
  const TileBuffer local = render_locally(spec);
  for (const int batch_ms : {0, 200}) {
    SCOPED_TRACE(batch_ms);
    test::TempDir dir;
    std::vector<UnitRecord> tiles;
    {
      EmbeddedFarmOptions options;
      options.data_dir = dir / "farm";
      options.threads = 2;
      options.exr_type = ExrPixelType::Float;
      options.batch_target = std::chrono::milliseconds(batch_ms);
      options.min_unit_edge = 0;
      EmbeddedFarm farm(options);
      for (const auto& [path, file] : test::cornell_assets()) farm.add_asset_file(file);
      const EmbeddedResult result = farm.run(spec);
      ASSERT_EQ(result.job.state(), v1::JOB_STATE_SUCCEEDED) << result.job.failure_reason();
      EXPECT_EQ(result.job.tiles_rendered(), 96u);
      expect_same_pixels(read_exr(result.exr), local, "merged");
      tiles = farm.core().store().units().tiles(result.job.job_id());  // the store lives in memory
    }
    ASSERT_EQ(tiles.size(), 96u);
    std::map<std::uint32_t, std::vector<const UnitRecord*>> calls;
    for (const UnitRecord& t : tiles) calls[t.part].push_back(&t);
    for (const auto& [part, members] : calls) {
      // A batch: consecutive tiles from its first on, whose union is one rectangle.
      Rect united = members[0]->rect;
      std::int64_t area = 0;
      for (std::size_t i = 0; i < members.size(); ++i) {
        EXPECT_EQ(members[i]->index, part + i);
        const Rect& r = members[i]->rect;
        united = {std::min(united.x0, r.x0), std::min(united.y0, r.y0), std::max(united.x1, r.x1),
                  std::max(united.y1, r.y1)};
        area += static_cast<std::int64_t>(r.width()) * r.height();
      }
      EXPECT_EQ(static_cast<std::int64_t>(united.width()) * united.height(), area) << "part " << part;
    }
    if (batch_ms == 0) {
      EXPECT_EQ(calls.size(), 96u);
    } else {
      EXPECT_LT(calls.size(), 48u) << "cheap tiles were not batched";
      EXPECT_GT(calls.size(), 8u) << "batches are at most one row";
    }
  }
}

// An in-process worker that counts how its calls came back: written into the frame's film
// (RenderedTiles::in_film) or as pixels of their own.
class CountingWorker final : public TileWorker {
 public:
  explicit CountingWorker(const TileRendererOptions& options) : inner_(options) {}
  grpc::Status render(const v1::RenderTileRequest& request, RenderedTiles& result,
                      std::chrono::system_clock::time_point deadline, TileCancel& cancel) override {
    const grpc::Status status = inner_.render(request, result, deadline, cancel);
    if (status.ok()) ++(result.in_film ? in_film : with_pixels);
    return status;
  }
  bool probe(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return "in-process"; }
  std::atomic<int> in_film{0}, with_pixels{0};

 private:
  InProcessTileWorker inner_;
};

// The embedded farm's worker pastes a frame's sub-tiles straight into the film the merge writes
// (FrameAssembly::film_to_render_into): every call of a frame without passes comes back written
// into it, none with a buffer of its own to copy, and the pixels are render_frame's. A frame of
// sample passes (folded in order), and a worker whose replies a spot check may hold, get no
// film: their calls bring their pixels as before, to the same frame.
TEST(EmbeddedFarmTest, ItsWorkerRendersStraightIntoTheFilmUnlessPassesOrSpotChecksNeedItsOwnPixels) {
  struct Case {
    std::string what, engine;
    int pass_spp;
    double verify_fraction;
    bool into_film;
  };
  for (const Case& c : {Case{"raster", "raster", 0, 0.0, true}, Case{"path, one pass", "path", 0, 0.0, true},
                        Case{"path in passes", "path", 1, 0.0, false},
                        Case{"spot checks on", "raster", 0, 1.0, false}}) {
    SCOPED_TRACE(c.what);
    test::TempDir dir;
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json(c.engine, 96, 64, 2));
    job["render"]["tile_size"] = 16;
    if (c.pass_spp > 0) job["render"]["pass_spp"] = c.pass_spp;
    const v1::JobSpec spec = test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json");
    SchedulerOptions options;
    options.data_dir = dir / "farm";
    options.log_level = LogLevel::warn;
    options.in_memory = true;
    options.exr_type = ExrPixelType::Float;
    options.verify_fraction = c.verify_fraction;
    options.batch_target = std::chrono::milliseconds(0);  // a call a unit: several calls a frame
    SchedulerCore core(options);
    test::add_cornell_assets(core);
    const auto worker =
        std::make_shared<CountingWorker>(test::in_process_worker_options(dir / "farm", dir / "worker", 2));
    core.add_worker(worker);
    const std::string id = core.submit(core.check(spec)).job_id();
    test::eventually([&] { return is_final(core.get_job(id)->state()); }, std::chrono::seconds(120));
    ASSERT_EQ(core.get_job(id)->state(), v1::JOB_STATE_SUCCEEDED) << core.get_job(id)->failure_reason();
    const int calls = worker->in_film + worker->with_pixels;
    EXPECT_GT(calls, 4);
    EXPECT_EQ(worker->in_film, c.into_film ? calls : 0);
    const std::optional<std::filesystem::path> exr = core.result_file(id, false);
    ASSERT_TRUE(exr.has_value());
    expect_same_pixels(read_exr(*exr), render_locally(spec), c.what);
  }
}

// What the in-memory film takes from a call that rendered into it: the part alone, its pixels
// being there already; a film it never handed out (or of another frame) is refused, and only the
// in-memory assembly hands films out, for frames without passes.
TEST(FrameAssemblyTest, BatchesRenderedIntoTheMemoryFilmAreRecordedNotCopied) {
  const v1::JobSpec spec = test::cornell_job_spec("whitted", 40, 30, 1);
  const Job job = parse_job(spec.job_json(), test::kSource / "jobs" / spec.file_name());
  const PreparedScene scene(build_scene(job));
  const FrameLayout frame{Rect{0, 0, 40, 30}, job.render.aovs};
  const TileBuffer local = render_frame(scene, job.render);
  InMemoryAssembly memory;
  const std::shared_ptr<TileBuffer> film = memory.film_to_render_into("job", frame);
  ASSERT_TRUE(film);
  EXPECT_EQ(film->rect(), frame.image);
  EXPECT_EQ(memory.film_to_render_into("job", frame), film) << "one film a frame";
  std::vector<FramePart> parts;
  const std::vector<Rect> tiles = split_into_tiles(40, 30, 13);
  for (std::uint32_t i = 0; i < tiles.size(); ++i) {
    TileBuffer tile;
    render_tile(scene, job.render, tiles[i], tile);
    film->paste(tile);  // as the in-process worker's render threads do
    RenderedTiles rendered;
    encode_stats(tile.stats(), *rendered.response.mutable_stats());
    rendered.film = film;
    rendered.in_film = true;
    memory.add("job", frame, {i, 0}, rendered);
    parts.push_back({i, 0});
  }
  const TileBuffer merged = memory.assemble("job", frame, parts);
  expect_same_pixels(merged, local, "rendered into the film");
  EXPECT_EQ(merged.stats().rays, local.stats().rays);

  RenderedTiles stray;
  stray.film = std::make_shared<TileBuffer>(frame.image, frame.aovs);  // not the assembly's
  stray.in_film = true;
  EXPECT_THROW(memory.add("other", frame, {0, 0}, stray), std::runtime_error);

  FrameLayout folded = frame;
  folded.passes = {SampleRange{0, 1}, SampleRange{1, 2}};
  EXPECT_EQ(memory.film_to_render_into("job", folded), nullptr);
  test::TempDir dir;
  TileFileAssembly files(dir / "tiles");
  EXPECT_EQ(files.film_to_render_into("job", frame), nullptr);
  RenderedTiles written;
  written.in_film = true;
  EXPECT_THROW(files.add("job", frame, {0, 0}, written), std::logic_error);
}

// Both places a job's tiles wait for the merge give the frame render_frame gives, from encoded
// tiles (a remote worker's) and from tiles as rendered (an in-process worker's) alike; a part
// the store lists but nobody kept is an error, not a hole in the image.
TEST(FrameAssemblyTest, FilesAndMemoryAssembleTheFrameRenderFrameGives) {
  test::TempDir dir;
  const v1::JobSpec spec = test::cornell_job_spec("whitted", 40, 30, 1);
  const Job job = parse_job(spec.job_json(), test::kSource / "jobs" / spec.file_name());
  const PreparedScene scene(build_scene(job));
  const FrameLayout frame{Rect{0, 0, 40, 30}, job.render.aovs};
  const TileBuffer local = render_frame(scene, job.render);
  const std::vector<Rect> tiles = split_into_tiles(40, 30, 13);
  TileFileAssembly files(dir / "tiles");
  InMemoryAssembly memory;
  for (FrameAssembly* assembly : std::initializer_list<FrameAssembly*>{&files, &memory}) {
    const std::string what = assembly == &files ? "files" : "memory";
    std::vector<FramePart> parts;
    for (std::uint32_t i = 0; i < tiles.size(); ++i) {
      TileBuffer tile;
      render_tile(scene, job.render, tiles[i], tile);
      RenderedTiles rendered;
      encode_stats(tile.stats(), *rendered.response.mutable_stats());
      if (i % 2 == 0) {
        encode_tile(tile, *rendered.response.mutable_tile());
      } else {
        rendered.pixels = std::move(tile);
      }
      assembly->add("job", frame, {i, 0}, rendered);
      parts.push_back({i, 0});
    }
    const TileBuffer merged = assembly->assemble("job", frame, parts);
    expect_same_pixels(merged, local, what);
    EXPECT_EQ(merged.stats().rays, local.stats().rays) << what;
    const MergedFiles written{dir / what / "frame.exr", dir / what / "frame.png"};
    write_merged(merged, written, ExrPixelType::Float);
    expect_same_pixels(read_exr(written.exr), local, what + ", written");
    EXPECT_TRUE(std::filesystem::exists(written.preview)) << what;

    parts.push_back({99, 0});  // a part nobody kept
    EXPECT_THROW(assembly->assemble("job", frame, parts), std::runtime_error) << what;
  }
}

// A frame of sample passes is the fold of its passes in sample order, whatever order its parts
// arrive in: both assemblies, given pass 2's tiles first and pass 0's last (in other tile splits
// than pass 1's), give render_frame's frame bit for bit, and a progressive fold of pass 0 alone
// is the frame of its samples (a render of spp 3).
TEST(FrameAssemblyTest, PassesArrivingInAnyOrderFoldToTheFrameRenderFrameGives) {
  test::TempDir dir;
  const v1::JobSpec spec = test::cornell_job_spec("path", 40, 30, 8);
  const Job job = parse_job(spec.job_json(), test::kSource / "jobs" / spec.file_name());
  const PreparedScene scene(build_scene(job));
  RenderSettings settings = job.render;
  settings.pass_spp = 3;  // passes [0, 3), [3, 6), [6, 8)
  ASSERT_EQ(pass_count(settings), 3);
  FrameLayout frame{Rect{0, 0, 40, 30}, settings.aovs, 0, {}};
  for (int p = 0; p < 3; ++p) frame.passes.push_back(pass_samples(settings, p));
  const TileBuffer local = render_frame(scene, settings);
  RenderSettings first_pass = job.render;
  first_pass.spp = 3;
  const TileBuffer pass0 = render_frame(scene, first_pass);

  struct Unit {
    int pass;
    Rect rect;
  };
  std::vector<Unit> units;
  for (int p : {2, 1, 0}) {
    for (const Rect& r : split_into_tiles(40, 30, p == 1 ? 16 : 13)) units.push_back({p, r});
  }
  TileFileAssembly files(dir / "tiles");
  InMemoryAssembly memory;
  for (FrameAssembly* assembly : std::initializer_list<FrameAssembly*>{&files, &memory}) {
    const std::string what = assembly == &files ? "files" : "memory";
    std::vector<FramePart> parts;
    for (std::uint32_t i = 0; i < units.size(); ++i) {
      RenderSettings s = settings;
      s.pass = units[i].pass;
      TileBuffer tile;
      render_tile(scene, s, units[i].rect, tile);
      RenderedTiles rendered;
      encode_stats(tile.stats(), *rendered.response.mutable_stats());
      encode_tile(tile, *rendered.response.mutable_tile());
      assembly->add("job", frame, {i, units[i].pass}, rendered);
      parts.push_back({i, units[i].pass});
    }
    // As the job store lists them: in pass order.
    std::stable_sort(parts.begin(), parts.end(), [](const FramePart& a, const FramePart& b) { return a.pass < b.pass; });
    if (assembly->reads_parts_back()) {
      PassAccumulator progressive(frame.image, frame.aovs);
      std::vector<FramePart> of_pass0;
      for (const FramePart& p : parts) {
        if (p.pass == 0) of_pass0.push_back(p);
      }
      assembly->fold("job", frame, of_pass0, progressive);
      expect_same_pixels(progressive.resolve(), pass0, what + ", pass 0");
    }
    const TileBuffer merged = assembly->assemble("job", frame, parts);
    expect_same_pixels(merged, local, what);
    EXPECT_EQ(merged.stats().samples, local.stats().samples) << what;
  }
}

}  // namespace
}  // namespace farm
