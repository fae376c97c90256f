#include "server/worker/tile_renderer.h"

#include <fmt/format.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string_view>

#include "renderer/engine.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "renderer/util/input_error.h"
#include "server/common/scene_hash.h"
#include "server/common/scene_materializer.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"
#include "server/common/tile_codec.h"

namespace farm {

namespace {

using Clock = std::chrono::steady_clock;

// Sub-tiles are the unit of parallelism: small enough that a 64x64 tile keeps 16 threads busy,
// large enough that per-tile engine overhead stays negligible. Cancellation reaches inside them:
// the engines poll the call's CancelFlag every few samples or triangles. Pixels do not depend on
// the split (the engine contract).
constexpr int kSubTile = 16;
// How often the waiting handler looks at its client (IsCancelled); the deadline needs no look,
// the render threads check it themselves.
constexpr auto kCancelPollInterval = std::chrono::milliseconds(10);
// 48 bytes a pixel with every AOV; keeps a reply far below protobuf's 2 GiB message limit.
constexpr std::int64_t kMaxRectPixels = std::int64_t{4096} * 4096;

double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// Why a call ended early: the caller's deadline passed, or it (or the server) cancelled.
grpc::Status stopped(const CancelFlag& flag) {
  if (flag.reason() == StopReason::Deadline) {
    return {grpc::StatusCode::DEADLINE_EXCEEDED, "deadline exceeded while rendering"};
  }
  return {grpc::StatusCode::CANCELLED, "cancelled while rendering"};
}

// One RenderTile call's sub-tiles in flight. Shared with the pool's work, so a call that returns
// early (cancelled) leaves the chunks still running a live buffer and flag until they stop.
struct RectRender {
  explicit RectRender(CancelFlag::Clock::time_point deadline) : flag(deadline) {}

  std::shared_ptr<const CachedScene> scene;
  RenderSettings settings;  // the scene's, at the call's sample pass
  std::vector<Rect> subs;
  std::atomic<std::size_t> next{0};  // the next sub-tile a render thread takes
  TileBuffer out;
  TileBuffer* into = &out;  // where sub-tiles are pasted: `out`, or the caller's film
  // The call's: cancelled by the handler when its client goes away (or a sub-tile fails); the
  // deadline is the client's. The engines poll it.
  CancelFlag flag;
  std::atomic<std::size_t> complete{0};  // sub-tiles rendered to the end and pasted into `into`

  std::mutex mutex;  // guards the three below
  RenderStats stats;
  double cpu_ms = 0.0;
  std::exception_ptr failure;
};

// The edge of the pieces a call's rect is rendered in. The rasterizer pays a set-up per tile and
// bin (walking the bin's triangles), which 16x16 pieces of its 32x32 bins would pay four times:
// it renders the job's own tiles whole (a batch's rect is a run of them) when the call holds at
// least one per render thread. The ray engines have no per-tile set-up worth sparing and keep the
// small pieces, which balance well.
int sub_tile_size(const RenderSettings& settings, const Rect& rect, int threads) {
  if (settings.engine != EngineKind::Raster) return kSubTile;
  const int tile = std::max(settings.tile_size, 1);
  const std::int64_t tiles = std::int64_t{(rect.width() + tile - 1) / tile} * ((rect.height() + tile - 1) / tile);
  return tiles >= threads ? std::max(tile, kSubTile) : kSubTile;
}

double thread_cpu_ms() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// One render thread's share of a call: it takes the call's sub-tiles one at a time until none
// is left (or the call stops), so the threads balance as finely as with a pool chunk a sub-tile,
// while the thread's CPU clock, a system call (0.6 us on a 2-core VM), is read twice a share
// rather than twice a sub-tile (28,800 reads for a 48-frame 640x480 turntable), and one tile
// buffer serves all its sub-tiles.
void render_share(RectRender& r) {
  RenderStats stats;
  const double cpu_start = thread_cpu_ms();
  TileBuffer tile;
  for (std::size_t i = 0; !r.flag.stop_requested() && (i = r.next.fetch_add(1)) < r.subs.size();) {
    try {
      // A stopped sub-tile comes back without pixels and is never pasted: `out` is incomplete
      // then, and the call says CANCELLED or DEADLINE_EXCEEDED instead of sending it.
      if (render_tile(r.scene->prepared, r.settings, r.subs[i], tile, r.flag) == StopReason::None) {
        r.into->paste(tile);  // sub-tiles are disjoint: no lock needed
        r.complete.fetch_add(1);
      }
      stats += tile.stats();
    } catch (...) {
      {
        // Recorded before the flag stops the others, so the handler reports this, not a cancel.
        std::lock_guard lock(r.mutex);
        if (!r.failure) r.failure = std::current_exception();
      }
      r.flag.cancel();
    }
  }
  const double cpu_ms = thread_cpu_ms() - cpu_start;
  std::lock_guard lock(r.mutex);
  r.stats += stats;
  r.cpu_ms += cpu_ms;
}

// Waits for `work` while polling the call's stop; false when it stopped first. Chunks not
// started are then skipped; those running see the flag within a few samples or triangles and
// return without pasting: the pool is free again in a millisecond or so.
bool finish_unless_stopped(ThreadPool::Work& work, const std::function<bool()>& is_stopped) {
  while (!work.wait_for(kCancelPollInterval)) {
    if (is_stopped()) {
      work.cancel();
      return false;
    }
  }
  return true;
}

// InputError naming the hash of an inline file the spec does not list: a worker keeps the files
// sent with a call, so one the job never reads would only fill its disk.
void check_inline_referenced(const v1::JobSpec& spec, const v1::RenderTileRequest& request) {
  if (request.assets().empty()) return;
  std::set<std::string_view> referenced;
  for (const v1::AssetRef& ref : spec.assets()) referenced.insert(ref.sha256());
  for (const v1::InlineAsset& asset : request.assets()) {
    if (referenced.contains(asset.sha256())) continue;
    throw InputError(fmt::format("inline asset sha256 '{}' ({} bytes) is none of the job's assets; "
                                 "the call's files were not kept",
                                 asset.sha256().substr(0, 64), asset.data().size()));
  }
}

// InputError naming the asset when inline bytes are not as long as the spec's AssetRef says.
void check_inline_sizes(const v1::JobSpec& spec, const v1::RenderTileRequest& request) {
  if (request.assets().empty()) return;
  std::map<std::string_view, const v1::InlineAsset*> inline_by_hash;
  for (const v1::InlineAsset& asset : request.assets()) inline_by_hash.emplace(asset.sha256(), &asset);
  for (const v1::AssetRef& ref : spec.assets()) {
    const auto it = inline_by_hash.find(ref.sha256());
    if (it == inline_by_hash.end() || it->second->data().size() == ref.size()) continue;
    throw InputError(fmt::format("inline asset '{}' (sha256 {}): {} bytes, the job says {}",
                                 ref.path().substr(0, 200), ref.sha256().substr(0, 64),
                                 it->second->data().size(), ref.size()));
  }
}

}  // namespace

TileRenderer::TileRenderer(const TileRendererOptions& options)
    : log_(make_logger("worker", options.log_level)),
      cache_dir_(options.cache_dir),
      store_(options.blobs_dir),
      fetcher_(options.schedulers.empty()
                   ? nullptr
                   : std::make_unique<AssetFetcher>(options.schedulers, options.scheduler_identity)),
      cache_({options.max_scenes, options.cache_memory_mb << 20}),
      pool_(options.threads) {
  // A worker killed mid-fetch left the fetch's temporary file in its store.
  if (const std::size_t swept = store_.sweep_abandoned_uploads()) {
    log_->info("removed {} fetch(es) cut short from {}", swept, store_.dir().string());
  }
}

void TileRenderer::scheduler_registered(const std::string& scheduler_id, const std::string& address) {
  if (fetcher_) fetcher_->learn(scheduler_id, address);
}

std::shared_ptr<const CachedScene> TileRenderer::prepare(const v1::JobSpec& spec, const std::string& hash,
                                                          const std::string& scheduler_id) {
  const Clock::time_point start = Clock::now();
  validate_asset_refs(spec);
  const std::vector<v1::AssetRef> missing = missing_assets(spec, store_);
  if (!missing.empty()) {
    if (!fetcher_) {
      throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                         fmt::format("{} on this worker, which has no --scheduler to fetch from",
                                     MissingAssetsError(missing).what()));
    }
  }
  std::string fetched_from;
  for (const v1::AssetRef& ref : missing) {
    const std::string from = fetcher_->fetch(ref, store_, scheduler_id);
    if (fetched_from.find(from) == std::string::npos) fetched_from += (fetched_from.empty() ? "" : ", ") + from;
  }
  MaterializedScene m = materialize_scene(spec, hash, store_, cache_dir_);
  LoadedScene loaded = load_job_scene(m.job);
  auto prepared =
      std::make_shared<const CachedScene>(std::move(m.job), std::move(loaded.scene), std::move(loaded.models));
  // Once per scene and worker: what an operator looks for when a job's first tiles are slow.
  log_->info("scene {} of job '{}' prepared in {:.0f} ms: {} triangles{}", hash.substr(0, 12),
             prepared->job.name, ms_since(start), prepared->prepared.triangle_count(),
             missing.empty() ? std::string()
                             : fmt::format(", {} files fetched from {}", missing.size(), fetched_from));
  return prepared;
}

std::shared_ptr<const CachedScene> TileRenderer::adopt(const std::string& scene_hash, Job job,
                                                         Scene scene, std::shared_ptr<ModelLibrary> models) {
  return cache_
      .get(scene_hash,
           [&] { return std::make_shared<const CachedScene>(std::move(job), std::move(scene), std::move(models)); },
           nullptr)
      .scene;
}

SceneCache::Lookup TileRenderer::frame_of(const std::string& hash, const SceneCache::Lookup& base, int frame,
                                          const SceneCache::Cancelled& cancelled) {
  const Job& job = base.scene->job;
  if (frame == job.frame) return base;
  if (!job.frames || !job.frames->contains(frame)) {
    throw InputError(job.frames ? fmt::format("frame {} is not one the job renders ({} to {} by {})", frame,
                                              job.frames->start, job.frames->end, job.frames->step)
                                : fmt::format("frame {} of a job without frames (a still is frame 0)", frame));
  }
  SceneCache::Lookup lookup = cache_.get(
      fmt::format("{}@{}", hash, frame),
      [&] {
        Job at = job_at_frame(job, frame);
        Scene scene = build_scene(at, *base.scene->models);
        return std::make_shared<const CachedScene>(std::move(at), std::move(scene), base.scene->models,
                                                   base.scene->prepared.shared_geometry());
      },
      cancelled);
  lookup.hit = lookup.hit && base.hit;
  return lookup;
}

grpc::Status TileRenderer::render(const v1::RenderTileRequest& request,
                                  v1::RenderTileResponse& response, const RenderControl& control) {
  TileBuffer pixels;
  grpc::Status status = render(request, pixels, *response.mutable_stats(), control);
  if (status.ok()) encode_tile(pixels, *response.mutable_tile());
  return status;
}

grpc::Status TileRenderer::render(const v1::RenderTileRequest& request, TileBuffer& pixels,
                                  v1::TileStats& stats, const RenderControl& control, TileBuffer* film) {
  const grpc::Status status = render_rect(request, pixels, stats, control, film);
  log_call(request, status, stats);
  return status;
}

void TileRenderer::log_call(const v1::RenderTileRequest& request, const grpc::Status& status,
                            const v1::TileStats& stats) const {
  // Only other failures are warnings. A cancelled call is the scheduler's decision (a job
  // cancelled, a worker dropped, a shutdown); a call for files this worker cannot fetch, or
  // without the job of a scene it no longer holds, is answered by the scheduler sending them
  // along with its next call.
  const grpc::StatusCode code = status.error_code();
  const bool expected = status.ok() || code == grpc::StatusCode::CANCELLED ||
                        code == grpc::StatusCode::FAILED_PRECONDITION || code == grpc::StatusCode::NOT_FOUND;
  const LogLevel level = expected ? LogLevel::debug : LogLevel::warn;
  if (!log_->should_log(level)) return;  // spares the formatting of every call
  const v1::TileRect& r = request.rect();
  log_->log(level, "job {} rect [{}, {}) x [{}, {}): {}", request.job_id(), r.x0(), r.x1(), r.y0(), r.y1(),
            status.ok() ? fmt::format("rendered in {:.0f} ms ({:.0f} ms CPU)", stats.render_ms(), stats.cpu_ms())
                        : fmt::format("{}: {}", status_code_name(code), status.error_message()));
}

grpc::Status TileRenderer::render_rect(const v1::RenderTileRequest& req, TileBuffer& pixels,
                                       v1::TileStats& stats, const RenderControl& control, TileBuffer* film) {
  const Clock::time_point start = Clock::now();
  const v1::RenderTileRequest* request = &req;
  auto r = std::make_shared<RectRender>(CancelFlag::steady_deadline(control.deadline));
  // The client's cancel becomes the flag's, which the render threads see.
  const auto is_stopped = [&] {
    if (control.cancelled && control.cancelled()) r->flag.cancel();
    return r->flag.stop_requested();
  };
  try {
    const v1::JobSpec& spec = request->job();
    // A call without its job is for a scene this worker prepared from an earlier call's job.
    const bool job_sent = request->has_job();
    if (!job_sent && !is_sha256_hex(request->scene_hash())) {
      return {grpc::StatusCode::INVALID_ARGUMENT,
              "a call without its job must name its scene_hash (64 lowercase hex digits)"};
    }
    if (!job_sent && request->assets_size() > 0) {
      return {grpc::StatusCode::INVALID_ARGUMENT, "inline files come only with the job that lists them"};
    }
    const std::string hash = job_sent ? scene_hash(spec) : request->scene_hash();
    if (job_sent && !request->scene_hash().empty() && request->scene_hash() != hash) {
      return {grpc::StatusCode::INVALID_ARGUMENT,
              fmt::format("scene_hash {} does not match the job spec's {}",
                          request->scene_hash().substr(0, 64), hash)};
    }
    const auto prepare_from_job = [&]() -> std::shared_ptr<const CachedScene> {
      if (!job_sent) {
        throw ServiceError(grpc::StatusCode::NOT_FOUND,
                           fmt::format("scene {} is not prepared on this worker: send its job", hash));
      }
      return prepare(spec, hash, request->scheduler_id());
    };

    // Files sent along by a scheduler we cannot fetch from: verified (their size against the
    // spec's, their hash), then kept like fetched ones.
    check_inline_referenced(spec, *request);
    check_inline_sizes(spec, *request);
    for (const v1::InlineAsset& asset : request->assets()) {
      if (!store_.has(asset.sha256())) store_.put(asset.sha256(), asset.data());
    }

    const SceneCache::Lookup job_lookup = [&] {
      try {
        return cache_.get(hash, prepare_from_job, is_stopped);
      } catch (const ServiceError& e) {
        // A concurrent call without the files (or without the job) failed the preparation this
        // one waited on, while this one brought them: with every file here now, prepare again.
        const bool retry = job_sent && (e.code() == grpc::StatusCode::NOT_FOUND ||
                                        (e.code() == grpc::StatusCode::FAILED_PRECONDITION &&
                                         missing_assets(spec, store_).empty()));
        if (!retry) throw;
        return cache_.get(hash, prepare_from_job, is_stopped);
      }
    }();
    if (!job_lookup.scene || is_stopped()) return stopped(r->flag);
    const SceneCache::Lookup lookup = frame_of(hash, job_lookup, request->frame(), is_stopped);
    if (!lookup.scene || is_stopped()) return stopped(r->flag);
    const double prepare_ms = lookup.hit ? 0.0 : ms_since(start);
    const RenderSettings& settings = lookup.scene->job.render;

    const v1::TileRect& tr = request->rect();
    const Rect rect = Rect{tr.x0(), tr.y0(), tr.x1(), tr.y1()}.intersect(
        Rect{0, 0, settings.width, settings.height});
    if (rect.empty()) {
      return {grpc::StatusCode::INVALID_ARGUMENT,
              fmt::format("rect [{}, {}) x [{}, {}) lies outside the {}x{} image or is empty",
                          tr.x0(), tr.x1(), tr.y0(), tr.y1(), settings.width, settings.height)};
    }
    if (std::int64_t{rect.width()} * rect.height() > kMaxRectPixels) {
      return {grpc::StatusCode::INVALID_ARGUMENT,
              fmt::format("rect of {}x{} pixels: at most {} pixels a call", rect.width(),
                          rect.height(), kMaxRectPixels)};
    }

    r->settings = settings;
    r->settings.pass = request->pass();
    // A pass outside the frame's (negative too) is InputError (INVALID_ARGUMENT), naming the passes.
    static_cast<void>(pass_samples(settings, request->pass()));

    const Clock::time_point render_start = Clock::now();
    r->scene = lookup.scene;
    // The engine's per-frame set-up (the rasterizer's transformed and binned triangles, the BVHs)
    // on all render threads, once per frame: the sub-tiles then find it built. It runs as pool
    // work so that this thread goes on polling the client's cancel, which the set-up sees
    // through the flag (it throws RenderStopped, kept by the work this call then abandons).
    const std::shared_ptr<ThreadPool::Work> setup =
        pool_.start(1, 1, [this, r, job_id = request->job_id()](std::size_t, std::size_t, int) {
          try {
            prepare_frame(r->scene->prepared, r->scene->job.render, pool_, r->flag);
          } catch (const RenderStopped& e) {
            log_->debug("job {}: the frame's set-up stopped: {}", job_id, e.what());
            throw;
          }
        });
    if (!finish_unless_stopped(*setup, is_stopped)) return stopped(r->flag);
    if (const std::exception_ptr failure = setup->failure()) {
      if (r->flag.stop_requested()) return stopped(r->flag);
      std::rethrow_exception(failure);
    }
    // Straight into the caller's film when it covers the rect with the render's AOVs; else into
    // a buffer of the call's own, handed back whole.
    if (film && film->rect().intersect(rect) == rect && film->aovs() == settings.aovs) {
      r->into = film;
    } else {
      r->out.reset_for_overwrite(rect, settings.aovs);
    }
    r->subs = split_into_tiles(rect.width(), rect.height(), sub_tile_size(settings, rect, pool_.size()));
    for (Rect& sub : r->subs) sub = {sub.x0 + rect.x0, sub.y0 + rect.y0, sub.x1 + rect.x0, sub.y1 + rect.y0};
    const std::size_t shares = std::min(static_cast<std::size_t>(pool_.size()), r->subs.size());
    const std::shared_ptr<ThreadPool::Work> work =
        pool_.start(shares, 1, [r](std::size_t begin, std::size_t end, int) {
          for (std::size_t i = begin; i < end; ++i) render_share(*r);
        });
    const bool finished = finish_unless_stopped(*work, is_stopped);
    // A sub-tile still running after a stop would paste into the film after the call has ended:
    // by then the film may be merged or gone. The stopped ones end within a few samples.
    if (r->into != &r->out) work->wait();
    {
      std::lock_guard lock(r->mutex);
      if (r->failure) std::rethrow_exception(r->failure);
    }
    // Only a tile whose every sub-tile ran to the end is sent: never a half-rendered one.
    if (!finished || r->complete.load() != r->subs.size()) return stopped(r->flag);
    // Every sub-tile has finished: r is ours alone now. (Into a film: `pixels` stays empty.)
    pixels = std::move(r->out);
    encode_stats(r->stats, stats);
    stats.set_render_ms(ms_since(render_start));
    stats.set_cpu_ms(r->cpu_ms);
    stats.set_prepare_ms(prepare_ms);
    stats.set_scene_cache_hit(lookup.hit);
    stats.set_threads(std::min<int>(pool_.size(), static_cast<int>(r->subs.size())));
    ++tiles_rendered_;
    return grpc::Status::OK;
  } catch (const std::exception&) {
    return status_of_current_exception();
  }
}

}  // namespace farm
