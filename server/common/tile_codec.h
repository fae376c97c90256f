#pragma once
// TileBuffer <-> farm.v1.TileData: each channel a plane of packed little-endian float32, row-major
// (proto/farm.proto). Bit-exact both ways, so a tile rendered by a worker merges into the same
// frame as one rendered in process.
#include "proto/farm.pb.h"
#include "renderer/image/tile_buffer.h"

namespace farm {

// A rect on the wire and back; the proto's fields are the same four corners.
v1::TileRect to_proto(const Rect& r);
Rect rect_of(const v1::TileRect& r);

void encode_tile(const TileBuffer& tile, v1::TileData& out);
void encode_stats(const RenderStats& stats, v1::TileStats& out);

// InputError when the rect is empty or a plane's size does not match it. AOVs are the non-empty
// planes.
TileBuffer decode_tile(const v1::TileData& data);
RenderStats decode_stats(const v1::TileStats& stats);

}  // namespace farm
