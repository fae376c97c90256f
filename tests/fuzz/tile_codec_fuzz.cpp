// The tile codec (server/common/tile_codec.cpp) and the scheduler's check of a worker's reply
// (tile_result_check.cpp): an input is a serialized farm.v1.RenderTileResponse, what a worker on
// another machine sends back. Properties, beyond not crashing:
//   - a tile that decodes re-encodes to a tile that decodes to the same bits (the codec is exact
//     both ways: a frame merged from remote tiles is bit-identical to one rendered in process);
//   - a reply that passes check_tile_reply decodes, and crops to any rectangle inside it.
#include <string>

#include "proto/farm.pb.h"
#include "renderer/job/render_settings.h"
#include "renderer/util/input_error.h"
#include "server/common/tile_codec.h"
#include "server/common/tile_result_check.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

using farm::fuzz::property_failed;

void check_round_trip(const farm::v1::TileData& data) {
  farm::TileBuffer decoded;
  try {
    decoded = farm::decode_tile(data);
  } catch (const farm::InputError&) {
    return;
  }
  farm::v1::TileData once;
  farm::encode_tile(decoded, once);
  farm::v1::TileData twice;
  farm::encode_tile(farm::decode_tile(once), twice);
  if (!farm::same_tile_bits(once, twice)) property_failed("decode(encode(tile)) changed its bits");
  if (!farm::same_tile_bits(once, data)) property_failed("a decoded tile re-encodes to other bits");
}

// The settings of a job that asks for the planes the reply carries, over a 64x64 image: so that a
// reply can pass the check, and the fuzzer can find one that passes wrongly.
farm::RenderSettings settings_for(const farm::v1::RenderTileResponse& reply) {
  farm::RenderSettings settings;
  settings.width = 64;
  settings.height = 64;
  const auto& t = reply.tile();
  settings.aovs.depth = !t.depth().empty();
  settings.aovs.normal = !t.normal().empty();
  settings.aovs.albedo = !t.albedo().empty();
  settings.aovs.bvh_cost = !t.bvh_cost().empty();
  settings.aovs.variance = !t.variance().empty();
  // Which engine: the stats say (path samples, ray counts), as a real reply's would.
  settings.engine = reply.stats().samples() > 0  ? farm::EngineKind::Path
                    : reply.stats().rays() > 0   ? farm::EngineKind::Whitted
                                                 : farm::EngineKind::Raster;
  return settings;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  farm::v1::RenderTileResponse reply;
  if (!reply.ParseFromArray(data, static_cast<int>(size))) return 0;
  check_round_trip(reply.tile());
  (void)farm::decode_stats(reply.stats());

  const farm::RenderSettings settings = settings_for(reply);
  const auto& r = reply.tile().rect();
  const farm::Rect asked{r.x0(), r.y0(), r.x1(), r.y1()};
  // The scheduler only asks for rectangles with pixels in the image (RenderTileRequest.rect).
  if (farm::answered_rect(settings, asked).empty()) return 0;
  if (!farm::check_tile_reply(reply, settings, asked).empty()) return 0;
  try {
    (void)farm::decode_tile(reply.tile());
  } catch (const farm::InputError& e) {
    property_failed(std::string("a reply that passed its check does not decode: ") + e.what());
  }
  // The scheduler crops a checked reply to the tiles of a batch (one row segment of it).
  const farm::Rect first_row{asked.x0, asked.y0, asked.x1, asked.y0 + 1};
  const farm::v1::TileData cropped = farm::crop_tile(reply.tile(), first_row);
  if (cropped.rgba().size() != static_cast<std::size_t>(asked.x1 - asked.x0) * 4 * sizeof(float)) {
    property_failed("a cropped row holds the wrong number of bytes");
  }
  return 0;
}
