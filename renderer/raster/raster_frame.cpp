#include "renderer/raster/raster_frame.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <unordered_map>
#include <utility>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <fmt/format.h>

#include "renderer/raster/view_culling.h"
#include "renderer/util/input_error.h"

namespace farm::raster {
namespace {

constexpr std::size_t kVertexGrain = 4096;
constexpr std::size_t kSetupGrain = 8192;
// The set-up looks at the cancel flag every kSetupUnitsPerPoll units of work, a unit being one
// triangle-in-bin entry filed and a triangle set up counting kUnitsPerTriangle (about their
// relative costs): a look every 256 small triangles, or every 8192 entries of a large one, tens
// of microseconds apart. A triangle that covers a 16384x16384 image fills 262,144 bins, so
// counting triangles alone would let one poll cover seconds of binning.
constexpr int kSetupUnitsPerPoll = 8192;
constexpr int kUnitsPerTriangle = 32;
// A chunk adds its bin entries to the frame's shared count once it has this many unreported (and
// at its end): one write to the shared cache line per tens of thousands of entries. One write
// per triangle, as before, made two threads slower than one (issue #32): the line bounced
// between the cores for every triangle. The frame may overshoot kMaxBinEntries by at most this
// much (plus one triangle's entries) per thread before the bound is seen.
constexpr std::uint64_t kEntriesPerReport = 1 << 16;

// One mesh of one object: where its vertices and triangles sit in the frame's flat numbering.
struct MeshRange {
  const PreparedObject* object;
  const Mesh* mesh;
  std::size_t first_vertex;
  std::size_t first_triangle;
  glm::mat4 to_clip;  // model to clip space: the vertex stage's, and clipping's again
  bool outside_view = false;  // wholly outside the view: its vertices and triangles are skipped
};

// The texture vertex at `p`, a point clipping made on triangle (a, b, c) with texture vertices
// (ta, tb, tc): its barycentric weights in the triangle's plane. The uvs are affine on the plane,
// so the clipped vertex gets what interpolating along the clipped edge would give.
TextureVertex texture_vertex_at(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c,
                                const TextureVertex& ta, const TextureVertex& tb, const TextureVertex& tc) {
  const glm::vec3 n = glm::cross(b - a, c - a);
  const float area = glm::dot(n, n);
  if (!(area > 0.0f)) return ta;
  const float wb = glm::dot(glm::cross(p - a, c - a), n) / area, wc = glm::dot(glm::cross(b - a, p - a), n) / area;
  const float wa = 1.0f - wb - wc;
  return {wa * ta.uv + wb * tb.uv + wc * tc.uv, wa * ta.tangent + wb * tb.tangent + wc * tc.tangent};
}

// What one set-up chunk produces, merged in chunk order afterwards. The chunks lie side by side
// in one vector and two threads write the counts of neighbouring ones for every triangle: each on
// cache lines of its own, or the lines bounce between the cores (false sharing, issue #32).
// The merge files each chunk's triangles in their bins from their pixel bounds, walking them in
// scene order; the set-up only counts the entries per bin. (A list of (bin, triangle) pairs made
// by the set-up cost 8 bytes an entry of fresh memory, 4.4 MB for a 1080p frame of the grid.)
struct alignas(64) SetupChunk {
  std::size_t first_slot = 0;    // its first input triangle's slot in RasterFrame::direct_triangles
  std::size_t direct_count = 0;  // triangles kept without clipping, in the slots from first_slot on
  std::vector<ScreenTriangle> from_clipping;
  // Per triangle of from_clipping: how many direct ones come before it in scene order.
  std::vector<std::uint32_t> direct_before;
  std::vector<ScreenVertex> clipped_vertices;
  std::vector<TextureVertex> clipped_textures;  // beside clipped_vertices, when the frame has uvs
  std::vector<std::uint32_t> bin_counts;        // entries per bin
  std::uint64_t unreported_entries = 0;  // filed here, not yet added to the frame's count
};

class FrameBuilder {
 public:
  FrameBuilder(const PreparedScene& scene, const RenderSettings& settings, RasterFrame& frame,
               const CancelFlag& cancel, SetupObserver* observer)
      : frame_(frame), cancel_(cancel), observer_(observer), centres_only_(settings.spp <= 1) {
    if (settings.width > kMaxImageSide || settings.height > kMaxImageSide) {
      // Positions on the sample grid are stored in 32 bits (SnappedPosition); jobs never get here.
      throw InputError(fmt::format("render: a {}x{} image is larger than the rasterizer's {} pixels a side",
                                   settings.width, settings.height, kMaxImageSide));
    }
    const Camera& camera = scene.scene().camera;
    view_ = camera.view_matrix();
    view_projection_ = camera.projection_matrix(camera.aspect_for(settings.width, settings.height)) * view_;
    frame.width = settings.width;
    frame.height = settings.height;
    frame.bins_x = (settings.width + kBinSize - 1) / kBinSize;
    frame.bins_y = (settings.height + kBinSize - 1) / kBinSize;
    frame.view_to_world = glm::inverse(view_);
    frame.eye = camera.position;
    std::size_t vertices = 0, triangles = 0;
    for (const PreparedObject& object : scene.placements()) {  // the meshes, not the flattened triangles
      for (const Mesh& mesh : object.source->model->meshes) {
        ranges_.push_back({&object, &mesh, vertices, triangles, view_projection_ * object.model_to_world});
        frame.materials.push_back(&object.source->materials.at(mesh.material));
        mirrored_.push_back(glm::determinant(glm::mat3(object.model_to_world)) < 0.0f);
        // Textured: the fragments carry texture coordinates, for the textures and for the alpha
        // a non-opaque material cuts fragments out by.
        textured_.push_back(frame.materials.back()->textures != nullptr ||
                            frame.materials.back()->alpha_mode != AlphaMode::Opaque);
        frame.textured = frame.textured || textured_.back();
        vertices += mesh.positions.size();
        triangles += mesh.triangles.size();
        has_uvs_ = has_uvs_ || !mesh.uvs.empty();
      }
    }
    if (vertices >= kClippedVertex || triangles >= kClippedTriangle) {  // the ids' flag bits
      throw InputError(fmt::format("render: the rasterizer takes fewer than {} vertices and triangles a "
                                   "frame; this scene has {} and {}", kClippedVertex, vertices, triangles));
    }
    // Meshes out of sight are skipped by both stages below (view_culling.h): each model's box is
    // worked out once, however many objects place it.
    std::unordered_map<const Mesh*, AABB> mesh_boxes;
    for (MeshRange& range : ranges_) {
      auto [box, fresh] = mesh_boxes.try_emplace(range.mesh);
      if (fresh) box->second = range.mesh->bounds();
      range.outside_view = wholly_outside_view(box->second, range.to_clip);
      if (range.outside_view) ++frame.meshes_outside_view;
    }
    frame.vertices.allocate(vertices);
    if (has_uvs_) frame.vertex_textures.resize(vertices);
    frame.input_triangles = triangles;
    frame.direct_triangles.allocate(triangles);
  }

  void run(ThreadPool* pool) {
    const auto parallel = [pool](std::size_t count, std::size_t grain, auto&& body) {
      const std::function<void(std::size_t, std::size_t, int)> fn = body;
      if (pool) {
        pool->parallel_for(count, grain, fn);
      } else {
        for (std::size_t b = 0; b < count; b += grain) fn(b, std::min(count, b + grain), 0);
      }
    };
    // Each step looks at the cancel flag per chunk (set-up: every few hundred triangles), and a
    // stop throws RenderStopped out of the pool's loop.
    const auto check = [this] {
      if (cancel_.stop_requested()) throw RenderStopped(cancel_.reason());
    };
    const auto observe = [this](SetupObserver::Stage stage, int worker, std::size_t items) {
      if (observer_) observer_->chunk(stage, worker, items);
    };
    parallel(frame_.vertices.size(), kVertexGrain, [&](std::size_t b, std::size_t e, int worker) {
      observe(SetupObserver::Stage::vertices, worker, e - b);
      check();
      transform_vertices(b, e);
    });
    chunks_.resize((frame_.input_triangles + kSetupGrain - 1) / kSetupGrain);
    parallel(frame_.input_triangles, kSetupGrain, [&](std::size_t b, std::size_t e, int worker) {
      observe(SetupObserver::Stage::triangles, worker, e - b);
      set_up(b, e, chunks_[b / kSetupGrain]);
    });
    check();
    plan_merge();
    frame_.setup_chunks = chunks_.size();
    parallel(chunks_.size(), 1, [&](std::size_t b, std::size_t e, int worker) {
      observe(SetupObserver::Stage::merge, worker, e - b);
      for (std::size_t c = b; c < e; ++c) {
        check();
        merge_chunk(c);
      }
    });
  }

 private:
  // The mesh range holding flat vertex or triangle index i.
  std::size_t range_of_vertex(std::size_t i) const {
    auto it = std::upper_bound(ranges_.begin(), ranges_.end(), i,
                               [](std::size_t v, const MeshRange& r) { return v < r.first_vertex; });
    return static_cast<std::size_t>(it - ranges_.begin()) - 1;
  }
  std::size_t range_of_triangle(std::size_t i) const {
    auto it = std::upper_bound(ranges_.begin(), ranges_.end(), i,
                               [](std::size_t t, const MeshRange& r) { return t < r.first_triangle; });
    return static_cast<std::size_t>(it - ranges_.begin()) - 1;
  }

  // Vertex i of the range's mesh in clip space: computed for the vertex stage and again for
  // clipping, by this one expression, so both see the same bits.
  static glm::vec4 clip_position(const MeshRange& range, std::size_t local) {
    return range.to_clip * glm::vec4(range.mesh->positions[local], 1.0f);
  }

  // Sets v's screen fields from its clip-space position c.
  void project(ScreenVertex& v, const glm::vec4& c) const {
    if (!(c.w > 0.0f)) return;  // behind the camera: only used after clipping
    v.inv_w = 1.0f / c.w;
    const float ndc_x = c.x * v.inv_w, ndc_y = c.y * v.inv_w;
    v.ndc_depth = c.z * v.inv_w;
    // Guard-band clipping keeps every rasterized vertex well inside the fixed-point range; the
    // margin covers rounding at the band's edge. Vertices beyond it are only ever clipped.
    if (std::fabs(ndc_x) <= 2.0f * kGuardBand && std::fabs(ndc_y) <= 2.0f * kGuardBand) {
      // Within 4.5 image sides of the corner: 32 bits hold it (SnappedPosition).
      v.position = {static_cast<std::int32_t>(to_fixed((ndc_x * 0.5f + 0.5f) * static_cast<float>(frame_.width))),
                    static_cast<std::int32_t>(to_fixed((0.5f - ndc_y * 0.5f) * static_cast<float>(frame_.height)))};
    }
  }

  void transform_vertices(std::size_t begin, std::size_t end) {
    std::size_t r = range_of_vertex(begin);
    while (begin < end) {
      while (begin >= ranges_[r].first_vertex + ranges_[r].mesh->positions.size()) ++r;
      const MeshRange& range = ranges_[r];
      const std::size_t stop = std::min(end, range.first_vertex + range.mesh->positions.size());
      if (range.outside_view) {  // no triangle of it reads them
        begin = stop;
        continue;
      }
      const glm::mat4 to_view = view_ * range.object->model_to_world;
      const glm::mat3& to_world_normal = range.object->normal_to_world;
      for (std::size_t i = begin; i < stop; ++i) {
        const std::size_t local = i - range.first_vertex;
        const glm::vec4 p(range.mesh->positions[local], 1.0f);
        ScreenVertex& v = frame_.vertices[i];
        const glm::vec4 clip = clip_position(range, local);
        v.view_position = glm::vec3(to_view * p);
        const glm::vec3 n = to_world_normal * range.mesh->normals[local];
        const float len = glm::length(n);
        v.world_normal = len > 0.0f ? n / len : n;
        if (has_uvs_) {
          TextureVertex& t = frame_.vertex_textures[i];
          t.uv = range.mesh->uvs.empty() ? glm::vec2(0.0f) : range.mesh->uvs[local];
          if (!range.mesh->tangents.empty()) {
            const glm::vec4& tangent = range.mesh->tangents[local];
            // Carried as the ray engines carry it (complete_surface_hit).
            const glm::mat3 linear(range.object->model_to_world);
            t.tangent = glm::vec4(linear * glm::vec3(tangent),
                                  (tangent.w < 0.0f) != (glm::determinant(linear) < 0.0f) ? -1.0f : 1.0f);
          }
        }
        v.outcode = outcode(clip);
        project(v, clip);
      }
      begin = stop;
    }
  }

  // While set-up runs, a clipped vertex index is local to its chunk; the merge rebases it.
  const ScreenVertex& vertex(const SetupChunk& chunk, std::uint32_t index) const {
    return (index & kClippedVertex) ? chunk.clipped_vertices[index & ~kClippedVertex] : frame_.vertices[index];
  }

  void emit(SetupChunk& chunk, CancelPoll& poll, bool from_clipping, std::uint32_t material,
            std::uint32_t i0, std::uint32_t i1, std::uint32_t i2) const {
    const FixedPoint p0 = vertex(chunk, i0).position.fixed(), p1 = vertex(chunk, i1).position.fixed(),
                     p2 = vertex(chunk, i2).position.fixed();
    const std::int64_t area = edge_function(p0, p1, p2);
    if (area == 0) return;  // covers no sample
    // Counter-clockwise seen from the front is clockwise on the y-down screen (area < 0), unless
    // the object's transform mirrors it (the front is where the model's winding says).
    const bool back_face = (area > 0) != static_cast<bool>(mirrored_[material]);
    if (area < 0) std::swap(i1, i2);
    ScreenTriangle t;
    t.v[0] = i0;
    t.v[1] = i1;
    t.v[2] = i2;
    t.material = material | (back_face ? kBackFace : 0u) | (textured_[material] ? kTexturedMaterial : 0u);
    const std::int64_t min_x = std::min({p0.x, p1.x, p2.x}), max_x = std::max({p0.x, p1.x, p2.x}),
                       min_y = std::min({p0.y, p1.y, p2.y}), max_y = std::max({p0.y, p1.y, p2.y});
    int x0, y0, x1, y1;
    if (centres_only_) {
      // Pixels whose centre lies in the bounding box: none means the triangle covers no sample.
      const std::int64_t centre = kSubpixelScale / 2;
      x0 = std::max(0, first_sample_pixel(min_x, centre));
      y0 = std::max(0, first_sample_pixel(min_y, centre));
      x1 = std::min(frame_.width - 1, last_sample_pixel(max_x, centre));
      y1 = std::min(frame_.height - 1, last_sample_pixel(max_y, centre));
    } else {
      // Every pixel a sample of which (at any sub-pixel offset) could fall inside.
      x0 = std::max(0, last_sample_pixel(min_x, 0));
      y0 = std::max(0, last_sample_pixel(min_y, 0));
      x1 = std::min(frame_.width - 1, last_sample_pixel(max_x, 0));
      y1 = std::min(frame_.height - 1, last_sample_pixel(max_y, 0));
    }
    if (x0 > x1 || y0 > y1) return;  // off screen, or between samples
    // Now within the image: 16 bits hold them.
    t.x0 = static_cast<std::uint16_t>(x0);
    t.y0 = static_cast<std::uint16_t>(y0);
    t.x1 = static_cast<std::uint16_t>(x1);
    t.y1 = static_cast<std::uint16_t>(y1);
    if (from_clipping) {
      chunk.from_clipping.push_back(t);
      chunk.direct_before.push_back(static_cast<std::uint32_t>(chunk.direct_count));
    } else {
      frame_.direct_triangles[chunk.first_slot + chunk.direct_count++] = t;
    }
    const int row_bins = x1 / kBinSize - x0 / kBinSize + 1;
    chunk.unreported_entries += static_cast<std::uint64_t>(y1 / kBinSize - y0 / kBinSize + 1) *
                                static_cast<std::uint64_t>(row_bins);
    if (chunk.unreported_entries >= kEntriesPerReport) report_entries(chunk);
    for_each_bin(t, poll, [&](std::size_t bin) { ++chunk.bin_counts[bin]; });
  }

  // Calls on_bin(bin) for every bin t's pixel bounds overlap, row by row, counting each row's bins
  // to `poll` first: the set-up counts the entries this way and the merge files them, in the
  // same order.
  template <typename OnBin>
  void for_each_bin(const ScreenTriangle& t, CancelPoll& poll, OnBin&& on_bin) const {
    const int bx0 = t.x0 / kBinSize, bx1 = t.x1 / kBinSize;
    for (int by = t.y0 / kBinSize; by <= t.y1 / kBinSize; ++by) {
      poll.throw_if_stopped(bx1 - bx0 + 1);
      const std::size_t row = static_cast<std::size_t>(by) * static_cast<std::size_t>(frame_.bins_x);
      for (int bx = bx0; bx <= bx1; ++bx) on_bin(row + static_cast<std::size_t>(bx));
    }
  }

  void set_up(std::size_t begin, std::size_t end, SetupChunk& chunk) const {
    chunk.first_slot = begin;
    chunk.bin_counts.assign(static_cast<std::size_t>(frame_.bins_x) * static_cast<std::size_t>(frame_.bins_y), 0);
    std::size_t r = range_of_triangle(begin);
    CancelPoll poll(cancel_, kSetupUnitsPerPoll);
    for (std::size_t i = begin; i < end; ++i) {
      poll.throw_if_stopped(kUnitsPerTriangle);
      while (i >= ranges_[r].first_triangle + ranges_[r].mesh->triangles.size()) ++r;
      const MeshRange& range = ranges_[r];
      if (range.outside_view) {  // every triangle of it would be dropped below
        i = std::min(end, range.first_triangle + range.mesh->triangles.size()) - 1;
        continue;
      }
      const glm::uvec3 local = range.mesh->triangles[i - range.first_triangle];
      const auto base = static_cast<std::uint32_t>(range.first_vertex);
      const std::uint32_t ia = base + local.x, ib = base + local.y, ic = base + local.z;
      const auto material = static_cast<std::uint32_t>(r);
      const ScreenVertex &a = frame_.vertices[ia], &b = frame_.vertices[ib], &c = frame_.vertices[ic];
      if (a.outcode & b.outcode & c.outcode) continue;  // wholly outside one plane
      if ((a.outcode | b.outcode | c.outcode) == 0) {
        emit(chunk, poll, false, material, ia, ib, ic);
        continue;
      }
      const auto clip_vertex = [&range](const ScreenVertex& v, std::uint32_t local_index) {
        return ClipVertex{clip_position(range, local_index), v.view_position, v.world_normal};
      };
      const ClippedPolygon poly =
          clip_triangle(clip_vertex(a, local.x), clip_vertex(b, local.y), clip_vertex(c, local.z));
      if (poly.size < 3) continue;
      const auto first = static_cast<std::uint32_t>(chunk.clipped_vertices.size()) | kClippedVertex;
      for (std::size_t k = 0; k < poly.size; ++k) {
        ScreenVertex v;
        v.view_position = poly.vertices[k].view_position;
        v.world_normal = poly.vertices[k].world_normal;
        v.outcode = 0;  // clipped: inside every plane
        project(v, poly.vertices[k].clip);
        chunk.clipped_vertices.push_back(v);
        if (has_uvs_) {
          chunk.clipped_textures.push_back(texture_vertex_at(
              v.view_position, a.view_position, b.view_position, c.view_position,
              frame_.vertex_textures[ia], frame_.vertex_textures[ib], frame_.vertex_textures[ic]));
        }
      }
      for (std::uint32_t k = 2; k < poly.size; ++k) {
        emit(chunk, poll, true, material, first, first + k - 1, first + k);
      }
    }
    report_entries(chunk);
  }

  // Adds the chunk's unreported bin entries to the frame's count (the one write every set-up
  // thread shares, kEntriesPerReport entries apart) and refuses a frame past kMaxBinEntries.
  void report_entries(SetupChunk& chunk) const {
    const std::uint64_t entries = std::exchange(chunk.unreported_entries, 0);
    if (entries == 0) return;
    if (observer_) observer_->shared_write();
    if (bin_entries_.fetch_add(entries, std::memory_order_relaxed) + entries > kMaxBinEntries) {
      throw InputError(fmt::format(
          "render: the rasterizer would file more than {} triangle-in-bin entries for this {}x{} "
          "frame (its triangles cover the image that many times over in {}-pixel bins); "
          "render a smaller image, or fewer large triangles",
          kMaxBinEntries, frame_.width, frame_.height, kBinSize));
    }
  }

  // Where each chunk's clipped vertices and bin entries go in the frame's arrays.
  void plan_merge() {
    const std::size_t bins = static_cast<std::size_t>(frame_.bins_x) * static_cast<std::size_t>(frame_.bins_y);
    vertex_base_.resize(chunks_.size());
    triangle_base_.resize(chunks_.size());
    std::size_t vertices = 0, triangles = 0;
    for (std::size_t c = 0; c < chunks_.size(); ++c) {
      vertex_base_[c] = vertices;
      vertices += chunks_[c].clipped_vertices.size();
      triangle_base_[c] = triangles;
      triangles += chunks_[c].from_clipping.size();
    }
    frame_.clipped_vertices.resize(vertices);
    if (has_uvs_) frame_.clipped_textures.resize(vertices);
    frame_.clipped_triangles.resize(triangles);  // fewer than the bin entries (kMaxBinEntries)

    // Counting sort by bin, stable in chunk order, so every bin lists triangles in scene order.
    // Loops run chunk by chunk so that each walks one contiguous count array.
    std::vector<std::uint32_t> running(bins, 0);
    for (const SetupChunk& chunk : chunks_)
      for (std::size_t b = 0; b < bins; ++b) running[b] += chunk.bin_counts[b];
    frame_.bin_start.assign(bins + 1, 0);
    std::uint32_t total = 0;
    for (std::size_t b = 0; b < bins; ++b) {
      frame_.bin_start[b] = total;
      total += running[b];
      running[b] = frame_.bin_start[b];
    }
    bin_cursor_.resize(chunks_.size() * bins);
    for (std::size_t c = 0; c < chunks_.size(); ++c) {
      for (std::size_t b = 0; b < bins; ++b) {
        bin_cursor_[c * bins + b] = running[b];
        running[b] += chunks_[c].bin_counts[b];
      }
    }
    frame_.bin_start[bins] = total;
    frame_.bin_triangles.allocate(total);
  }

  // Copies the chunk's clipped vertices and triangles to the frame (rebasing the triangles'
  // indices of clipped vertices), and files all its triangles in their bins in scene order.
  void merge_chunk(std::size_t c) {
    SetupChunk& chunk = chunks_[c];
    const std::size_t bins = frame_.bin_start.size() - 1;
    const auto vertex_base = static_cast<std::uint32_t>(vertex_base_[c]);
    std::copy(chunk.clipped_vertices.begin(), chunk.clipped_vertices.end(),
              frame_.clipped_vertices.begin() + static_cast<std::ptrdiff_t>(vertex_base));
    std::copy(chunk.clipped_textures.begin(), chunk.clipped_textures.end(),
              frame_.clipped_textures.begin() + static_cast<std::ptrdiff_t>(vertex_base));
    const std::size_t triangle_base = triangle_base_[c];
    for (std::size_t k = 0; k < chunk.from_clipping.size(); ++k) {
      ScreenTriangle& tri = frame_.clipped_triangles[triangle_base + k];
      tri = chunk.from_clipping[k];
      // Only triangles made by clipping use clipped vertices.
      for (std::uint32_t& v : tri.v) {
        if (v & kClippedVertex) v = kClippedVertex | (vertex_base + (v & ~kClippedVertex));
      }
    }
    std::uint32_t* cursor = &bin_cursor_[c * bins];
    CancelPoll poll(cancel_, kSetupUnitsPerPoll);  // a large triangle files many thousand entries
    const auto file = [&](const ScreenTriangle& t, std::size_t id) {
      for_each_bin(t, poll, [&](std::size_t bin) { frame_.bin_triangles[cursor[bin]++] = static_cast<std::uint32_t>(id); });
    };
    // The direct triangles in their slots and the clipped ones between them, in scene order.
    std::size_t k = 0;
    for (std::size_t d = 0; d <= chunk.direct_count; ++d) {
      for (; k < chunk.from_clipping.size() && chunk.direct_before[k] == d; ++k) {
        file(chunk.from_clipping[k], kClippedTriangle | (triangle_base + k));
      }
      if (d < chunk.direct_count) file(frame_.direct_triangles[chunk.first_slot + d], chunk.first_slot + d);
    }
  }

  RasterFrame& frame_;
  const CancelFlag& cancel_;
  SetupObserver* observer_;
  bool centres_only_;  // spp 1: a triangle between pixel centres can be dropped here
  bool has_uvs_ = false;  // some mesh has texture coordinates: the frame keeps them
  glm::mat4 view_{1.0f}, view_projection_{1.0f};
  std::vector<MeshRange> ranges_;
  std::vector<std::uint8_t> mirrored_;  // per range: its object's transform flips handedness
  std::vector<std::uint8_t> textured_;  // per range: its material has textures
  std::vector<SetupChunk> chunks_;
  std::vector<std::size_t> vertex_base_;    // per chunk: its first clipped vertex in the frame's
  std::vector<std::size_t> triangle_base_;  // per chunk: its first clipped triangle in the frame's
  std::vector<std::uint32_t> bin_cursor_;
  // Bin entries filed so far by every chunk, reported kEntriesPerReport at a time: bounded, as
  // their memory and the tiles' work grow with it (a frame's total must also fit the 32-bit bin
  // cursors). Last and aligned: a cache line of its own, away from the fields every thread reads.
  alignas(64) mutable std::atomic<std::uint64_t> bin_entries_{0};  // counted by the const set-up steps
};

}  // namespace

Rect RasterFrame::bin_rect(int bx, int by) const {
  return Rect{bx * kBinSize, by * kBinSize, std::min(width, (bx + 1) * kBinSize),
              std::min(height, (by + 1) * kBinSize)};
}

std::shared_ptr<const RasterFrame> build_raster_frame(const PreparedScene& scene,
                                                      const RenderSettings& settings,
                                                      ThreadPool* pool, const CancelFlag& cancel,
                                                      SetupObserver* observer) {
  auto frame = std::make_shared<RasterFrame>();
  FrameBuilder builder(scene, settings, *frame, cancel, observer);
  builder.run(pool);
  return frame;
}

}  // namespace farm::raster
