#include "server/scheduler/frame_assembly.h"

#include <climits>

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "server/common/tile_codec.h"

namespace farm {

namespace {

// A batch's pixels as a buffer: as rendered when they came from this process, else decoded.
TileBuffer pixels_of(RenderedTiles& tiles) {
  if (tiles.pixels) return std::move(*tiles.pixels);
  return decode_tile(tiles.response.tile());
}

void check_fits(const TileBuffer& tile, const FrameLayout& frame, const std::string& job_id,
                std::uint32_t part) {
  if (tile.rect().empty() || tile.rect().intersect(frame.image) != tile.rect()) {
    throw std::runtime_error(fmt::format("result {} of job {} lies outside the image", part, job_id));
  }
}

std::string describe(const std::vector<DamagedParts::Part>& parts) {
  std::string s = fmt::format("{} damaged result{}:", parts.size(), parts.size() == 1 ? "" : "s");
  for (const DamagedParts::Part& p : parts) s += " " + p.problem + ";";
  s.pop_back();
  return s;
}

}  // namespace

DamagedParts::DamagedParts(std::vector<Part> parts) : std::runtime_error(describe(parts)), parts_(std::move(parts)) {}

void TileFileAssembly::add(const std::string& job_id, const FrameLayout&, std::uint32_t part,
                           RenderedTiles& tiles) {
  // A worker in this process hands over pixels, not TileData: the file needs them encoded.
  if (tiles.pixels) {
    encode_tile(*tiles.pixels, *tiles.response.mutable_tile());
    tiles.pixels.reset();
  }
  files_.write(job_id, part, tiles.response);
}

TileBuffer TileFileAssembly::assemble(const std::string& job_id, const FrameLayout& frame,
                                      const std::vector<std::uint32_t>& parts) {
  TileBuffer film;
  // The parts cover the image exactly (tiles of split_into_tiles, in batches), so the film need
  // not be cleared first.
  film.reset_for_overwrite(frame.image, frame.aovs);
  std::vector<DamagedParts::Part> damaged;
  for (std::uint32_t part : parts) {
    RenderedTiles tiles;
    try {
      tiles.response = files_.read(job_id, part);
    } catch (const DamagedTileResult& e) {
      damaged.push_back({part, e.what()});  // the others are read too: all go back at once
      continue;
    }
    const TileBuffer buffer = pixels_of(tiles);
    check_fits(buffer, frame, job_id, part);
    film.paste(buffer);
    film.stats() += decode_stats(tiles.response.stats());
  }
  if (!damaged.empty()) throw DamagedParts(std::move(damaged));
  return film;
}

void InMemoryAssembly::add(const std::string& job_id, const FrameLayout& frame, std::uint32_t part,
                           RenderedTiles& tiles) {
  std::shared_ptr<Film> f;
  {
    std::lock_guard lock(mutex_);
    std::shared_ptr<Film>& slot = films_[{job_id, frame.frame}];
    if (!slot) {
      slot = std::make_shared<Film>();
      // The batches cover the image exactly: no clearing needed.
      slot->film.reset_for_overwrite(frame.image, frame.aovs);
    }
    f = slot;
  }
  const TileBuffer buffer = pixels_of(tiles);
  check_fits(buffer, frame, job_id, part);
  f->film.paste(buffer);  // batches are disjoint: concurrent pastes touch different pixels
  std::lock_guard lock(f->mutex);
  f->parts.emplace_back(part, decode_stats(tiles.response.stats()));
}

void InMemoryAssembly::discard(const std::string& job_id, std::uint32_t part) {
  std::vector<std::shared_ptr<Film>> films;  // the job's: part numbers are unique across its frames
  {
    std::lock_guard lock(mutex_);
    for (auto it = films_.lower_bound({job_id, INT_MIN}); it != films_.end() && it->first.first == job_id; ++it) {
      films.push_back(it->second);
    }
  }
  for (const std::shared_ptr<Film>& f : films) {
    std::lock_guard lock(f->mutex);
    // The oldest paste of the part: one pasted again since is the one that stays.
    const auto it = std::find_if(f->parts.begin(), f->parts.end(), [&](const auto& p) { return p.first == part; });
    if (it != f->parts.end()) {
      f->parts.erase(it);
      return;
    }
  }
}

TileBuffer InMemoryAssembly::assemble(const std::string& job_id, const FrameLayout& frame,
                                      const std::vector<std::uint32_t>& parts) {
  std::shared_ptr<Film> f;
  {
    std::lock_guard lock(mutex_);
    const auto it = films_.find({job_id, frame.frame});
    if (it != films_.end()) f = it->second;
  }
  if (!f) throw std::runtime_error(fmt::format("job {}: no tiles were kept for frame {}", job_id, frame.frame));
  std::lock_guard lock(f->mutex);
  std::vector<std::uint32_t> kept;
  RenderStats stats;
  for (const auto& [part, part_stats] : f->parts) {
    kept.push_back(part);
    stats += part_stats;
  }
  std::sort(kept.begin(), kept.end());
  std::vector<std::uint32_t> wanted = parts;
  std::sort(wanted.begin(), wanted.end());
  // The store and the film must agree on what was rendered, as the files would.
  if (kept != wanted || f->film.rect() != frame.image) {
    throw std::runtime_error(fmt::format("job {}: {} batches kept in memory, the job store lists {}",
                                         job_id, kept.size(), wanted.size()));
  }
  f->film.stats() = stats;
  return std::move(f->film);
}

void InMemoryAssembly::remove_job(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  films_.erase(films_.lower_bound({job_id, INT_MIN}), films_.lower_bound({job_id + '\0', INT_MIN}));
}

void InMemoryAssembly::frame_merged(const std::string& job_id, int frame) {
  std::lock_guard lock(mutex_);
  films_.erase({job_id, frame});
}

}  // namespace farm
