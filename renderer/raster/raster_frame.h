#pragma once
// The front half of the sort-middle rasterizer, done once per frame and shared by every tile:
// the vertex stage (all vertices to clip, view and world space), triangle set-up (clipping,
// snapping to the fixed-point grid, orientation) and binning of the set-up triangles to square
// screen bins. A tile then only rasterizes the triangles binned to the bins it overlaps.
//
// Triangles keep their scene order inside every bin, and each pixel sees exactly the triangles
// that can cover it in that order, so depth ties resolve the same way for any tiling.
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <memory>
#include <vector>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/image_limits.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "renderer/raster/clip_polygon.h"
#include "renderer/raster/edge_function.h"
#include "renderer/util/cancel_flag.h"
#include "renderer/util/thread_pool.h"
#include "renderer/util/uninitialized_array.h"

namespace farm::raster {

// Edge of a square screen bin in pixels. Small enough that a tile's bins carry few triangles
// that miss it, large enough that a typical triangle lands in one bin.
inline constexpr int kBinSize = 32;

// A vertex's place on the sample grid, 32 bits a coordinate (the rasterizer's edge functions
// widen it to FixedPoint's 64). A vertex gets one only within twice the guard band, i.e. at most
// 4.5 image sides from the image's corner, and the frame refuses an image side beyond
// kMaxImageSide, so every coordinate fits.
struct SnappedPosition {
  std::int32_t x, y;
  FixedPoint fixed() const { return {x, y}; }
};
static_assert(std::int64_t{5} * kMaxImageSide * kSubpixelScale < std::int64_t{1} << 31);

// A vertex after the vertex stage: what the tiles read of it, 44 bytes. Its screen fields are set
// only when it lies inside the guard band in front of the camera; a vertex outside is only ever
// used through clipping, which works out its clip-space position again from the mesh (the tiles
// never need it: 16 bytes a vertex, 4.7 MB of a 1080p frame of the 100-cow grid, not written).
struct ScreenVertex {
  SnappedPosition position;
  float ndc_depth;
  float inv_w;
  glm::vec3 view_position;
  glm::vec3 world_normal;
  std::uint8_t outcode;  // clip planes it lies outside of
};
static_assert(sizeof(ScreenVertex) == 44);

// Marks a triangle's vertex index as one into RasterFrame::clipped_vertices.
inline constexpr std::uint32_t kClippedVertex = 0x80000000u;

// A triangle ready to rasterize: positively oriented on the sample grid, non-degenerate, and
// (when only pixel centres are sampled) covering at least the bounding box of one centre.
// Marks a triangle's material index when the camera sees the triangle's back face.
inline constexpr std::uint32_t kBackFace = 0x80000000u;
// Marks a triangle's material index when the material has textures (the rasterizer then keeps
// texture coordinates), so that no triangle's material is looked at while drawing to know.
inline constexpr std::uint32_t kTexturedMaterial = 0x40000000u;
inline constexpr std::uint32_t kMaterialIndex = ~(kBackFace | kTexturedMaterial);

// What a textured surface's vertex adds: its texture coordinates, and its tangent frame in world
// space (Mesh::tangents carried by the object's transform; zero where the mesh has none).
struct TextureVertex {
  glm::vec2 uv{0.0f};
  glm::vec4 tangent{0.0f};
};

struct ScreenTriangle {
  std::uint32_t v[3];            // RasterFrame::vertex() indices
  std::uint32_t material;        // index into RasterFrame::materials, | kBackFace, | kTexturedMaterial
  // Pixels whose samples it may cover, inclusive, in the image (of at most kMaxImageSide a side).
  std::uint16_t x0, y0, x1, y1;
};
static_assert(kMaxImageSide <= 65536 && sizeof(ScreenTriangle) == 24);

// Marks a triangle id in RasterFrame::bin_triangles as an index into RasterFrame::clipped_triangles;
// without it, the id is the input triangle's slot in RasterFrame::direct_triangles.
inline constexpr std::uint32_t kClippedTriangle = 0x80000000u;

struct RasterFrame {
  int width = 0, height = 0;
  int bins_x = 0, bins_y = 0;
  glm::mat4 view_to_world{1.0f};
  glm::vec3 eye{0.0f};
  UninitializedArray<ScreenVertex> vertices;  // one per scene vertex
  std::vector<ScreenVertex> clipped_vertices;  // made by clipping, in scene order
  // One slot per input triangle, written where the triangle needs no clipping and is kept: one
  // block (recycled frame memory, in huge pages) rather than one a set-up chunk, whose 4 KiB pages
  // each faulted on first touch: 4,600 faults, a quarter of a fresh `farm render` of the 100-cow
  // grid's (72 chunks of 256 KiB). Only the slots the bins name are read.
  UninitializedArray<ScreenTriangle> direct_triangles;
  std::vector<ScreenTriangle> clipped_triangles;  // the fans of clipped triangles, in scene order
  std::vector<const Material*> materials;
  // Texture coordinates and tangent frames beside the vertices, kept apart so that scenes without
  // them pay nothing per vertex: one per scene vertex and one per clipped vertex, or none when no
  // mesh has texture coordinates.
  std::vector<TextureVertex> vertex_textures;
  std::vector<TextureVertex> clipped_textures;
  bool textured = false;  // some material has textures (with or without texture coordinates)
  // Bin b holds the triangle ids bin_triangles[bin_start[b] .. bin_start[b + 1]), in scene order:
  // 4 bytes an entry rather than a pointer's 8.
  std::vector<std::uint32_t> bin_start;
  UninitializedArray<std::uint32_t> bin_triangles;
  std::size_t setup_chunks = 0;  // how many pieces the set-up split the triangles into

  const ScreenTriangle& triangle(std::uint32_t id) const {
    return (id & kClippedTriangle) ? clipped_triangles[id & ~kClippedTriangle] : direct_triangles[id];
  }

  const ScreenVertex& vertex(std::uint32_t i) const {
    return (i & kClippedVertex) ? clipped_vertices[i & ~kClippedVertex] : vertices[i];
  }

  TextureVertex texture_vertex(std::uint32_t i) const {
    if (vertex_textures.empty()) return TextureVertex{};
    return (i & kClippedVertex) ? clipped_textures[i & ~kClippedVertex] : vertex_textures[i];
  }

  void prefetch_vertices(const ScreenTriangle& t) const {
    for (std::uint32_t v : t.v) __builtin_prefetch(&vertex(v));
  }

  std::size_t input_triangles = 0;  // before clipping and culling of invisible ones
  // Meshes (one per object and mesh) wholly outside the view, skipped before the vertex stage.
  std::size_t meshes_outside_view = 0;

  Rect bin_rect(int bx, int by) const;
};

// At most this many (triangle, bin) entries in a frame: 256 MiB of triangle ids, and far more than
// an honest scene files (each triangle lands in one bin or a few: a 10M-triangle model at 4K
// files about 20M). Beyond it, the frame is refused with an InputError that says why, before its
// memory or its tiles' work can grow with resolution x triangle area.
inline constexpr std::uint64_t kMaxBinEntries = std::uint64_t{1} << 26;

// What the set-up's threads did, counted: how each stage was split across the pool's threads and
// how often a thread wrote state the others share. Tests hold the set-up to scaling with these
// counts rather than with a clock (raster_setup_split_test.cpp). Called from the pool's threads.
class SetupObserver {
 public:
  enum class Stage { vertices, triangles, merge };
  virtual ~SetupObserver() = default;
  // Before a chunk of `items` (vertices, triangles, or set-up chunks merged) runs on pool thread
  // `worker` (0 when there is no pool).
  virtual void chunk(Stage stage, int worker, std::size_t items) = 0;
  // A write to a counter every set-up thread writes (the frame's bin-entry budget): such writes
  // bounce a cache line between cores, so there must be few per chunk, not one per triangle.
  virtual void shared_write() = 0;
};

// Builds the frame's set-up on `pool` (or on the calling thread when null). Polls `cancel` every
// few hundred triangles or few thousand bin entries filed, and throws RenderStopped when it asks;
// throws InputError for a frame of more than kMaxBinEntries bin entries.
std::shared_ptr<const RasterFrame> build_raster_frame(const PreparedScene& scene,
                                                      const RenderSettings& settings,
                                                      ThreadPool* pool, const CancelFlag& cancel,
                                                      SetupObserver* observer = nullptr);

}  // namespace farm::raster
