// check_tile_reply (server/common/tile_result_check.h): real engine output passes, with every AOV;
// every kind of reply no engine makes is refused with a reason that says what is wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "renderer/job/job.h"
#include "server/common/asset_store.h"
#include "server/common/tile_result_check.h"
#include "server/worker/tile_renderer.h"
#include "tests/support/fake_worker.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

float get(const std::string& plane, std::size_t index) {
  float v;
  std::memcpy(&v, plane.data() + index * sizeof v, sizeof v);
  return v;
}

void set(std::string& plane, std::size_t index, float v) { std::memcpy(plane.data() + index * sizeof v, &v, sizeof v); }

// A job of the example scenes with every AOV: the Cornell box (every pixel hits the box) or the
// two tori (background around them).
struct Scene {
  std::string json;
  std::vector<std::pair<std::string, fs::path>> assets;
};

Scene cornell(const std::string& engine, int spp) {
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json(engine, 40, 30, spp));
  job["output"]["aovs"] = {"depth", "normal", "albedo", "bvh_cost", "variance"};
  return {job.dump(), test::cornell_assets()};
}

Scene tori(const std::string& engine, int spp) {
  nlohmann::json job = nlohmann::json::parse(test::read_file(fs::path(FARM_SOURCE_DIR) / "jobs/torus.json"));
  job["render"] = {{"engine", engine}, {"width", 48}, {"height", 30}, {"spp", spp}};
  job["output"]["aovs"] = {"depth", "normal", "albedo", "bvh_cost", "variance"};
  return {job.dump(), {{"assets/torus.gltf", fs::path(FARM_SOURCE_DIR) / "jobs/assets/torus.gltf"}}};
}

// Renders `rect` of `scene` the way a `farm worker` does (TileRenderer), the reply as it would
// travel, and the settings the scheduler checks it against.
class RealReply : public ::testing::Test {
 protected:
  v1::RenderTileResponse render(const Scene& scene, Rect rect) {
    const AssetStore blobs(dir_ / "blobs");
    for (const auto& [path, file] : scene.assets) blobs.add(test::read_file(file));
    TileRendererOptions options;
    options.blobs_dir = dir_ / "blobs";
    options.cache_dir = dir_ / "cache";
    options.threads = 2;
    options.log_level = LogLevel::warn;
    TileRenderer renderer(options);
    v1::RenderTileRequest request;
    *request.mutable_job() = test::make_job_spec(scene.json, scene.assets, "job.json");
    request.mutable_rect()->set_x0(rect.x0);
    request.mutable_rect()->set_y0(rect.y0);
    request.mutable_rect()->set_x1(rect.x1);
    request.mutable_rect()->set_y1(rect.y1);
    v1::RenderTileResponse reply;
    const grpc::Status status = renderer.render(request, reply, RenderControl{});
    EXPECT_TRUE(status.ok()) << status.error_message();
    // The settings the scheduler has: the job parsed where its files lie (the example jobs).
    settings_ = parse_job(scene.json, fs::path(FARM_SOURCE_DIR) / "jobs" / "job.json").render;
    return reply;
  }

  std::string check(const v1::RenderTileResponse& reply, Rect asked) const {
    return check_tile_reply(reply, settings_, asked);
  }

  test::TempDir dir_;
  RenderSettings settings_;
};

// Every engine, one sample and several, every AOV, a scene with and one without background.
TEST_F(RealReply, EveryEngineWithEveryAovPasses) {
  for (const std::string engine : {"raster", "whitted", "path"}) {
    for (int spp : {1, 3, 4}) {
      for (const bool with_background : {false, true}) {
        const Scene scene = with_background ? tori(engine, spp) : cornell(engine, spp);
        const Rect whole{0, 0, with_background ? 48 : 40, 30};
        const v1::RenderTileResponse reply = render(scene, whole);
        EXPECT_EQ(check(reply, whole), "") << engine << " spp " << spp << (with_background ? " tori" : " cornell");
        if (with_background) {
          // The tori leave background around them: misses are checked too.
          bool miss = false;
          for (std::size_t i = 0; i < 48u * 30u; ++i) miss = miss || std::isinf(get(reply.tile().depth(), i));
          EXPECT_TRUE(miss);
        }
      }
    }
  }
}

TEST_F(RealReply, ARectOverTheImageEdgeIsAnsweredClippedAndPasses) {
  const Rect asked{32, 16, 64, 48};  // the image is 40 x 30
  const v1::RenderTileResponse reply = render(cornell("whitted", 1), asked);
  EXPECT_EQ(answered_rect(settings_, asked), (Rect{32, 16, 40, 30}));
  EXPECT_EQ(check(reply, asked), "");
}

// Each lie the fake worker tells is refused, saying what is wrong.
TEST_F(RealReply, EveryLieOfTheFakeWorkerIsRefusedWithItsReason) {
  const Rect rect{8, 8, 24, 16};
  const v1::RenderTileResponse honest = render(cornell("path", 2), rect);
  ASSERT_EQ(check(honest, rect), "");
  const std::vector<std::pair<test::Lie, std::string>> lies{
      {test::Lie::ShiftedRect, "its rect [9, 25) x [8, 16) is not the [8, 24) x [8, 16) asked for"},
      {test::Lie::MissingPlane, "its normal plane is missing"},
      {test::Lie::ShortPlane, "its depth plane holds 508 bytes, not the 512 of 16x8 pixels"},
      {test::Lie::NaN, "pixel (8, 8): rgba plane: R is NaN"},
      {test::Lie::NegativeDepth, "pixel (8, 8): depth plane: -1"},
  };
  for (const auto& [lie, reason] : lies) {
    v1::RenderTileResponse reply = honest;
    test::tell_lie(lie, reply);
    EXPECT_NE(check(reply, rect).find(reason), std::string::npos) << to_string(lie) << ": " << check(reply, rect);
  }
  // Plausible pixels pass: only a spot check can catch them.
  v1::RenderTileResponse reply = honest;
  test::tell_lie(test::Lie::FlippedBits, reply);
  EXPECT_FALSE(same_tile_bits(reply.tile(), honest.tile()));
  EXPECT_EQ(check(reply, rect), "");
  // bvh_cost is an AOV this job asks for; one that does not gets a plane it did not ask for.
  nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("path", 40, 30, 2));
  reply = render({job.dump(), test::cornell_assets()}, rect);
  ASSERT_EQ(check(reply, rect), "");
  test::tell_lie(test::Lie::ExtraPlane, reply);
  EXPECT_EQ(check(reply, rect), "its bvh_cost plane holds 512 bytes; the job did not ask for it");
}

// Values no engine writes, one plane at a time. `pixel` picks a hit (or a miss) of the tori.
TEST_F(RealReply, ValuesNoEngineWritesAreRefused) {
  const Rect rect{0, 0, 48, 30};
  const v1::RenderTileResponse whitted = render(tori("whitted", 1), rect);
  ASSERT_EQ(check(whitted, rect), "");
  std::optional<std::size_t> hit, miss;
  for (std::size_t i = 0; i < 48u * 30u; ++i) {
    (std::isinf(get(whitted.tile().depth(), i)) ? miss : hit) = i;
  }
  ASSERT_TRUE(hit && miss);
  const auto refused = [&](const v1::RenderTileResponse& base, const std::function<void(v1::TileData&)>& change,
                           const std::string& reason) {
    v1::RenderTileResponse reply = base;
    change(*reply.mutable_tile());
    const std::string why = check(reply, rect);
    EXPECT_NE(why.find(reason), std::string::npos) << "expected '" << reason << "', got '" << why << "'";
  };
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_rgba(), 4 * *hit + 1, kInf); }, "rgba plane: G is +inf");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_rgba(), 4 * *hit + 3, 1.5f); }, "A (coverage) is 1.5, outside [0, 1]");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_rgba(), 4 * *hit + 3, 0.5f); }, "A is 0.5 with one sample a pixel");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_depth(), *hit, kNaN); }, "depth plane: NaN");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_depth(), *hit, -kInf); }, "depth plane: -inf");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_depth(), *hit, -3e38f); }, "depth plane: -3e+38");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_normal(), 3 * *hit, 22048.0f); }, "normal plane: (22048");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_normal(), 3 * *hit + 2, kNaN); }, "is not finite");
  refused(whitted, [&](v1::TileData& t) { for (int c = 0; c < 3; ++c) set(*t.mutable_normal(), 3 * *hit + c, 0.0f); },
          "normal plane: (0, 0, 0) where depth says hit");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_normal(), 3 * *miss, 1.0f); }, "where depth says no hit");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_albedo(), 3 * *hit, kInf); }, "albedo plane: (+inf");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_albedo(), 3 * *miss + 1, 0.25f); }, "where nothing was hit");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_bvh_cost(), *hit, 2.5f); }, "bvh_cost plane: 2.5 is no count");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_bvh_cost(), *hit, -4.0f); }, "bvh_cost plane: -4 is no count");
  refused(whitted, [&](v1::TileData& t) { set(*t.mutable_variance(), 3 * *hit, 0.125f); },
          "variance plane: 0.125 from the whitted engine, which writes 0");
  refused(whitted, [&](v1::TileData& t) { t.mutable_rect()->set_y1(31); }, "its rect [0, 48) x [0, 31) is not");
  refused(whitted, [&](v1::TileData& t) { t.set_width(47); }, "its size 47x30 is not its rect's 48x30");

  const v1::RenderTileResponse path = render(tori("path", 2), rect);
  ASSERT_EQ(check(path, rect), "");
  refused(path, [&](v1::TileData& t) { set(*t.mutable_variance(), 3 * *hit, -1e-6f); }, "variance plane: -1e-06");
  refused(path, [&](v1::TileData& t) { set(*t.mutable_bvh_cost(), *hit, 7.0f); }, "bvh_cost plane: 7 from the path engine");
  const auto stats_refused = [&](const std::function<void(v1::TileStats&)>& change, const std::string& reason) {
    v1::RenderTileResponse reply = path;
    change(*reply.mutable_stats());
    const std::string why = check(reply, rect);
    EXPECT_NE(why.find(reason), std::string::npos) << "expected '" << reason << "', got '" << why << "'";
  };
  stats_refused([](v1::TileStats& s) { s.set_cpu_ms(kNaN); }, "stats: cpu_ms is nan");
  stats_refused([](v1::TileStats& s) { s.set_render_ms(-1.0); }, "stats: render_ms is -1");
  stats_refused([](v1::TileStats& s) { s.set_samples(s.samples() + 1); }, "stats: 2881 samples, the path engine takes 2880");
  stats_refused([](v1::TileStats& s) { s.set_invalid_samples(s.samples() + 1); }, "invalid samples of 2880");
}

TEST(TileResultCheck, SameBitsAndCropSeeEveryPlane) {
  v1::TileData a;
  a.mutable_rect()->set_x0(2);
  a.mutable_rect()->set_y0(1);
  a.mutable_rect()->set_x1(6);
  a.mutable_rect()->set_y1(3);
  a.set_width(4);
  a.set_height(2);
  a.set_rgba(std::string(4 * 2 * 16, '\0'));
  a.set_depth(std::string(4 * 2 * 4, '\0'));
  a.set_normal(std::string(4 * 2 * 12, '\0'));
  for (std::size_t i = 0; i < 8; ++i) set(*a.mutable_depth(), i, static_cast<float>(i));
  v1::TileData b = a;
  EXPECT_TRUE(same_tile_bits(a, b));
  set(*b.mutable_normal(), 5, -0.0f);  // the same value, not the same bits
  EXPECT_FALSE(same_tile_bits(a, b));

  const v1::TileData crop = crop_tile(a, Rect{3, 1, 5, 3});
  EXPECT_EQ(crop.width(), 2);
  EXPECT_EQ(crop.height(), 2);
  ASSERT_EQ(crop.depth().size(), 4u * 4u);
  // Row y=1: pixels x=3, 4 are a's 1 and 2; row y=2: a's 5 and 6.
  EXPECT_EQ(get(crop.depth(), 0), 1.0f);
  EXPECT_EQ(get(crop.depth(), 1), 2.0f);
  EXPECT_EQ(get(crop.depth(), 2), 5.0f);
  EXPECT_EQ(get(crop.depth(), 3), 6.0f);
  EXPECT_EQ(crop.rgba().size(), 2u * 2u * 16u);
  EXPECT_TRUE(crop.albedo().empty());
}

}  // namespace
}  // namespace farm
