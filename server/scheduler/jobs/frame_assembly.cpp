#include "server/scheduler/jobs/frame_assembly.h"

#include <climits>

#include <fmt/format.h>

#include <algorithm>
#include <functional>
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

const SampleRange& samples_of(const FrameLayout& frame, const FramePart& part, const std::string& job_id) {
  if (part.pass < 0 || static_cast<std::size_t>(part.pass) >= frame.passes.size()) {
    throw std::runtime_error(fmt::format("result {} of job {} is of pass {}; frame {} has {}", part.part, job_id,
                                         part.pass, frame.frame, frame.passes.size()));
  }
  return frame.passes[static_cast<std::size_t>(part.pass)];
}

std::string describe(const std::vector<DamagedParts::Part>& parts) {
  std::string s = fmt::format("{} damaged result{}:", parts.size(), parts.size() == 1 ? "" : "s");
  for (const DamagedParts::Part& p : parts) s += " " + p.problem + ";";
  s.pop_back();
  return s;
}

}  // namespace

DamagedParts::DamagedParts(std::vector<Part> parts) : std::runtime_error(describe(parts)), parts_(std::move(parts)) {}

void TileFileAssembly::add(const std::string& job_id, const FrameLayout&, const FramePart& part,
                           RenderedTiles& tiles) {
  if (tiles.in_film) throw std::logic_error("TileFileAssembly::add: a batch written into a film it never handed out");
  // A worker in this process hands over pixels, not TileData: the file needs them encoded.
  if (tiles.pixels) {
    encode_tile(*tiles.pixels, *tiles.response.mutable_tile());
    tiles.pixels.reset();
  }
  files_.write(job_id, part.part, tiles.response);
}

TileBuffer TileFileAssembly::assemble(const std::string& job_id, const FrameLayout& frame,
                                      const std::vector<FramePart>& parts) {
  TileBuffer film;
  RenderStats stats;  // the parts' own, summed
  if (frame.folded()) {
    PassAccumulator merged(frame.image, frame.aovs);
    read_parts(job_id, frame, parts, [&](const FramePart& part, const TileBuffer& buffer, const v1::TileStats& s) {
      merged.add(buffer, samples_of(frame, part, job_id));
      stats += decode_stats(s);
    });
    merged.resolve(film);
  } else {
    // The parts cover the image exactly (tiles of split_into_tiles, in batches), so the film need
    // not be cleared first.
    film.reset_for_overwrite(frame.image, frame.aovs);
    read_parts(job_id, frame, parts, [&](const FramePart&, const TileBuffer& buffer, const v1::TileStats& s) {
      film.paste(buffer);
      stats += decode_stats(s);
    });
  }
  film.stats() = stats;
  return film;
}

TileBuffer TileFileAssembly::assemble_partial(const std::string& job_id, const FrameLayout& frame,
                                              const std::vector<FramePart>& parts) {
  if (frame.folded()) throw std::logic_error("a frame of sample passes has its progressive preview instead");
  TileBuffer film;
  film.reset(frame.image, frame.aovs);  // cleared: the parts cover only part of it
  read_parts(job_id, frame, parts, [&](const FramePart&, const TileBuffer& buffer, const v1::TileStats&) {
    film.paste(buffer);
  });
  return film;
}

void TileFileAssembly::fold(const std::string& job_id, const FrameLayout& frame, const std::vector<FramePart>& parts,
                            PassAccumulator& into) {
  read_parts(job_id, frame, parts, [&](const FramePart& part, const TileBuffer& buffer, const v1::TileStats&) {
    into.add(buffer, samples_of(frame, part, job_id));
  });
}

void TileFileAssembly::read_parts(
    const std::string& job_id, const FrameLayout& frame, const std::vector<FramePart>& parts,
    const std::function<void(const FramePart&, const TileBuffer&, const v1::TileStats&)>& use) {
  std::vector<DamagedParts::Part> damaged;
  for (const FramePart& part : parts) {
    RenderedTiles tiles;
    try {
      tiles.response = files_.read(job_id, part.part);
    } catch (const DamagedTileResult& e) {
      damaged.push_back({part.part, e.what()});  // the others are read too: all go back at once
      continue;
    }
    // After a damaged part nothing more is used (a fold could not take the parts of later
    // passes over it), but every part is read, so that all the damaged ones are named at once.
    if (!damaged.empty()) continue;
    const TileBuffer buffer = pixels_of(tiles);
    check_fits(buffer, frame, job_id, part.part);
    use(part, buffer, tiles.response.stats());
  }
  if (!damaged.empty()) throw DamagedParts(std::move(damaged));
}

std::shared_ptr<InMemoryAssembly::Film> InMemoryAssembly::film_of(const std::string& job_id, int frame) {
  std::lock_guard lock(mutex_);
  const auto it = films_.find({job_id, frame});
  return it != films_.end() ? it->second : nullptr;
}

std::shared_ptr<TileBuffer> InMemoryAssembly::film_to_render_into(const std::string& job_id,
                                                                  const FrameLayout& frame) {
  if (frame.folded()) return nullptr;
  std::lock_guard lock(mutex_);
  std::shared_ptr<Film>& slot = films_[{job_id, frame.frame}];
  if (!slot) slot = std::make_shared<Film>();
  // The batches cover the image exactly: no clearing needed.
  if (slot->film.rect().empty()) slot->film.reset_for_overwrite(frame.image, frame.aovs);
  return std::shared_ptr<TileBuffer>(slot, &slot->film);
}

void InMemoryAssembly::add(const std::string& job_id, const FrameLayout& frame, const FramePart& part,
                           RenderedTiles& tiles) {
  if (tiles.in_film) {
    // Its pixels are in the film already (film_to_render_into): only the part is recorded.
    const std::shared_ptr<Film> f = film_of(job_id, frame.frame);
    if (!f || tiles.film.get() != &f->film) {
      throw std::runtime_error(fmt::format("result {} of job {} was rendered into a film frame {} no longer has",
                                           part.part, job_id, frame.frame));
    }
    std::lock_guard lock(f->mutex);
    f->parts.emplace_back(part.part, decode_stats(tiles.response.stats()));
    return;
  }
  TileBuffer buffer = pixels_of(tiles);
  check_fits(buffer, frame, job_id, part.part);
  std::shared_ptr<Film> f;
  {
    std::lock_guard lock(mutex_);
    std::shared_ptr<Film>& slot = films_[{job_id, frame.frame}];
    if (!slot) {
      slot = std::make_shared<Film>();
      if (!frame.folded() && buffer.rect() == frame.image && buffer.aovs() == frame.aovs) {
        // One batch is the whole frame (a small frame of the embedded farm's large units): its
        // pixels become the film, neither copied nor the film allocated for them.
        slot->film = std::move(buffer);
        slot->parts.emplace_back(part.part, decode_stats(tiles.response.stats()));
        return;
      }
      // The batches cover the image exactly: no clearing needed.
      if (frame.folded()) {
        slot->fold.reset(frame.image, frame.aovs);
      } else {
        slot->film.reset_for_overwrite(frame.image, frame.aovs);
      }
    }
    f = slot;
  }
  if (!frame.folded()) {
    f->film.paste(buffer);  // batches are disjoint: concurrent pastes touch different pixels
    std::lock_guard lock(f->mutex);
    f->parts.emplace_back(part.part, decode_stats(tiles.response.stats()));
    return;
  }
  static_cast<void>(samples_of(frame, part, job_id));
  std::lock_guard lock(f->mutex);
  f->waiting.push_back({part, std::move(buffer)});
  fold_waiting(*f, frame);
  f->parts.emplace_back(part.part, decode_stats(tiles.response.stats()));
}

void InMemoryAssembly::fold_waiting(Film& f, const FrameLayout& frame) {
  // Passes fold in pass order: the lowest waiting pass first, so one fold can free the next.
  std::sort(f.waiting.begin(), f.waiting.end(),
            [](const Waiting& a, const Waiting& b) { return a.part.pass < b.part.pass; });
  for (bool folded = true; folded;) {
    folded = false;
    for (auto it = f.waiting.begin(); it != f.waiting.end(); ++it) {
      const SampleRange& samples = frame.passes[static_cast<std::size_t>(it->part.pass)];
      if (!f.fold.can_add(it->pixels.rect(), samples)) continue;
      f.fold.add(it->pixels, samples);
      f.waiting.erase(it);
      folded = true;
      break;
    }
  }
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
      if (f->fold.rect().empty()) return;
      // A frame of passes: a part still waiting goes with it; one folded cannot be taken out.
      const auto waiting = std::find_if(f->waiting.begin(), f->waiting.end(),
                                        [&](const Waiting& w) { return w.part.part == part; });
      if (waiting != f->waiting.end()) {
        f->waiting.erase(waiting);
      } else {
        f->lost_folded_part = true;
      }
      return;
    }
  }
}

TileBuffer InMemoryAssembly::assemble(const std::string& job_id, const FrameLayout& frame,
                                      const std::vector<FramePart>& parts) {
  const std::shared_ptr<Film> f = film_of(job_id, frame.frame);
  if (!f) throw std::runtime_error(fmt::format("job {}: no tiles were kept for frame {}", job_id, frame.frame));
  std::lock_guard lock(f->mutex);
  std::vector<std::uint32_t> kept;
  RenderStats stats;
  for (const auto& [part, part_stats] : f->parts) {
    kept.push_back(part);
    stats += part_stats;
  }
  std::sort(kept.begin(), kept.end());
  std::vector<std::uint32_t> wanted;
  for (const FramePart& p : parts) wanted.push_back(p.part);
  std::sort(wanted.begin(), wanted.end());
  if (f->lost_folded_part) {
    throw std::runtime_error(fmt::format("job {}: frame {} lost a sample pass's tiles after they were folded in "
                                         "memory, and cannot be merged without them",
                                         job_id, frame.frame));
  }
  // The store and the film must agree on what was rendered, as the files would.
  const Rect& rect = frame.folded() ? f->fold.rect() : f->film.rect();
  if (kept != wanted || rect != frame.image || !f->waiting.empty()) {
    throw std::runtime_error(fmt::format("job {}: {} batches kept in memory ({} not folded), the job store lists {}",
                                         job_id, kept.size(), f->waiting.size(), wanted.size()));
  }
  if (frame.folded()) f->fold.resolve(f->film);
  f->film.stats() = stats;
  // Taken whole; what stays is an empty film (no rect), never one moved from.
  TileBuffer merged = std::move(f->film);
  f->film = TileBuffer();
  return merged;
}

std::uintmax_t InMemoryAssembly::remove_job(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  films_.erase(films_.lower_bound({job_id, INT_MIN}), films_.lower_bound({job_id + '\0', INT_MIN}));
  return 0;
}

void InMemoryAssembly::frame_merged(const std::string& job_id, int frame) {
  std::lock_guard lock(mutex_);
  films_.erase({job_id, frame});
}

}  // namespace farm
