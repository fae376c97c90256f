#pragma once
// Where a job's finished batches of tiles wait for the merge, and how they become its frame.
//
// - TileFileAssembly (the farm): each batch is a file (TileResults) written before its tiles are
//   marked done, so a restarted scheduler merges what an earlier process rendered.
// - InMemoryAssembly (the embedded farm of `farm render`): each batch is pasted into the job's
//   film as it arrives, or rendered straight into it by the worker in this process
//   (film_to_render_into); a frame of sample passes is folded, see below. Nothing is encoded, written,
//   read back or decoded; nothing survives the process, which `farm render` does not need (its
//   job store lives in memory too).
//
// A frame of several sample passes is the fold of its passes in sample order (PassAccumulator),
// pixel by pixel: the same arithmetic on the same floats whichever parts came first, so the
// merged frame is bit-identical however its units were spread.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/image/pass_merge.h"
#include "renderer/image/tile_buffer.h"
#include "server/scheduler/jobs/tile_results.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/workers/tile_worker.h"

namespace farm {

// Parts whose kept data cannot be read back (TileFileAssembly: the file is missing, truncated or
// fails its checksum). Their tiles are to be rendered again; nothing of them may be merged.
class DamagedParts : public std::runtime_error {
 public:
  struct Part {
    std::uint32_t part = 0;
    std::string problem;  // names the file
  };
  explicit DamagedParts(std::vector<Part> parts);
  const std::vector<Part>& parts() const { return parts_; }

 private:
  std::vector<Part> parts_;
};

// The frame a batch of tiles belongs to.
struct FrameLayout {
  Rect image;  // {0, 0, width, height}
  AovSet aovs;
  int frame = 0;  // the frame number (a still: 0)
  // Each sample pass's samples (pass_samples), in pass order; one entry: no passes to fold.
  std::vector<SampleRange> passes{SampleRange{0, 1}};
  bool folded() const { return passes.size() > 1; }
};

class FrameAssembly {
 public:
  virtual ~FrameAssembly() = default;
  // Keeps one batch (the part is its first tile index; its pass one of frame.passes). Throws
  // when it cannot: the batch is then not marked done.
  virtual void add(const std::string& job_id, const FrameLayout& frame, const FramePart& part,
                   RenderedTiles& tiles) = 0;
  // The frame's film, for a worker in this process to render a batch straight into (its call
  // then comes back `in_film`, and add() only records it); null where batches are kept apart.
  virtual std::shared_ptr<TileBuffer> film_to_render_into(const std::string&, const FrameLayout&) { return nullptr; }
  // The job's frame from its parts (each once, as the job store lists them: every pass's), with
  // the render statistics summed. DamagedParts (every such part, once all are read) when parts'
  // kept data is damaged; std::runtime_error when a part was never kept or does not fit.
  virtual TileBuffer assemble(const std::string& job_id, const FrameLayout& frame,
                              const std::vector<FramePart>& parts) = 0;
  // Whether parts can be read back once kept (fold()): not the embedded farm's, which keeps
  // only the merge's pixels.
  virtual bool reads_parts_back() const = 0;
  // The frame (not of sample passes) as far as `parts` cover it, black elsewhere: the dashboard's
  // live image of a frame being rendered. Throws as assemble() does, and std::logic_error unless
  // reads_parts_back().
  virtual TileBuffer assemble_partial(const std::string& job_id, const FrameLayout& frame,
                                      const std::vector<FramePart>& parts) = 0;
  // Folds `parts` (of passes the accumulator, sized to the frame, does not hold yet, in pass
  // order) into `into`: a frame's progressive preview. Throws as assemble() does, and
  // std::logic_error unless reads_parts_back().
  virtual void fold(const std::string& job_id, const FrameLayout& frame, const std::vector<FramePart>& parts,
                    PassAccumulator& into) = 0;
  // Forgets the job (done, or deleted); returns the bytes of kept data freed.
  virtual std::uintmax_t remove_job(const std::string& job_id) = 0;
  // The frame is merged and written: what is kept of it only for the merge may go.
  virtual void frame_merged(const std::string& job_id, int frame) = 0;
  // The part's tiles are no longer done (their worker was quarantined, or the store refused
  // them): whatever replaces them is added under its own part, maybe the same number.
  virtual void discard(const std::string& job_id, std::uint32_t part) = 0;
  // The parts' tiles were taken back to make room on a full disk, while dispatch is paused (so
  // nothing replaces them meanwhile): their kept data goes now.
  virtual void free_parts(const std::string& job_id, const std::vector<std::uint32_t>& parts) = 0;
};

class TileFileAssembly final : public FrameAssembly {
 public:
  explicit TileFileAssembly(std::filesystem::path dir) : files_(std::move(dir)) {}
  void add(const std::string& job_id, const FrameLayout& frame, const FramePart& part,
           RenderedTiles& tiles) override;
  TileBuffer assemble(const std::string& job_id, const FrameLayout& frame,
                      const std::vector<FramePart>& parts) override;
  bool reads_parts_back() const override { return true; }
  TileBuffer assemble_partial(const std::string& job_id, const FrameLayout& frame,
                              const std::vector<FramePart>& parts) override;
  void fold(const std::string& job_id, const FrameLayout& frame, const std::vector<FramePart>& parts,
            PassAccumulator& into) override;
  std::uintmax_t remove_job(const std::string& job_id) override { return files_.remove_job(job_id); }
  // The files stay until the job ends: a quarantine may yet take back some of the frame's parts,
  // and its merge again needs the rest.
  void frame_merged(const std::string&, int) override {}
  // Nothing to do: assemble() reads only the parts the store lists for done tiles, and a part
  // rendered again is written over the old file. Deleting the file here could delete its
  // replacement, written meanwhile under the same part.
  void discard(const std::string&, std::uint32_t) override {}
  void free_parts(const std::string& job_id, const std::vector<std::uint32_t>& parts) override {
    for (std::uint32_t part : parts) files_.remove(job_id, part);
  }

 private:
  // Reads each part back and hands it to `use` in order. DamagedParts names every damaged one,
  // once all are read; after the first, nothing more is used.
  void read_parts(const std::string& job_id, const FrameLayout& frame, const std::vector<FramePart>& parts,
                  const std::function<void(const FramePart&, const TileBuffer&, const v1::TileStats&)>& use);
  TileResults files_;
};

// A frame of sample passes is folded as its parts arrive, never kept pass by pass (a frame of 64
// passes would hold 64 films): a part is folded as soon as every pixel under it holds the passes
// before its own, and waits until then otherwise. A part discarded after it was folded (a
// quarantine, room made on a full disk) cannot be taken out again: the frame's merge then fails
// the job, saying so, rather than merging wrong pixels.
class InMemoryAssembly final : public FrameAssembly {
 public:
  void add(const std::string& job_id, const FrameLayout& frame, const FramePart& part,
           RenderedTiles& tiles) override;
  // A frame without passes to fold: its film, made now if no batch has come yet. The embedded
  // worker's sub-tiles are pasted into it as they finish, so a batch needs no buffer of its own
  // and the dispatcher's thread copies nothing (the 100-cow grid: 19 MiB of batch buffers at the
  // peak, and 33 MB copied, gone).
  std::shared_ptr<TileBuffer> film_to_render_into(const std::string& job_id, const FrameLayout& frame) override;
  TileBuffer assemble(const std::string& job_id, const FrameLayout& frame,
                      const std::vector<FramePart>& parts) override;
  bool reads_parts_back() const override { return false; }
  TileBuffer assemble_partial(const std::string&, const FrameLayout&, const std::vector<FramePart>&) override {
    throw std::logic_error("the embedded farm keeps no parts to assemble again");
  }
  void fold(const std::string&, const FrameLayout&, const std::vector<FramePart>&, PassAccumulator&) override {
    throw std::logic_error("the embedded farm keeps no parts to fold again");
  }
  std::uintmax_t remove_job(const std::string& job_id) override;  // returns 0: nothing on disk
  void frame_merged(const std::string& job_id, int frame) override;  // its film goes
  void discard(const std::string& job_id, std::uint32_t part) override;
  void free_parts(const std::string& job_id, const std::vector<std::uint32_t>& parts) override {
    for (std::uint32_t part : parts) discard(job_id, part);
  }

 private:
  struct Waiting {
    FramePart part;
    TileBuffer pixels;
  };
  struct Film {
    std::mutex mutex;  // guards parts, and with passes everything; pastes are of disjoint rects
    TileBuffer film;
    // Pasted (or folded) so far, in order, with their statistics. A part discarded and pasted
    // again is listed twice until the older one is discarded: the newer pixels are the ones in
    // the film.
    std::vector<std::pair<std::uint32_t, RenderStats>> parts;
    // A frame of passes: the fold so far, the parts waiting for the passes under them, and
    // whether a folded part was discarded (the fold is then wrong for good).
    PassAccumulator fold;
    std::vector<Waiting> waiting;
    bool lost_folded_part = false;
  };
  // Folds every waiting part that can be, until none can. Under f.mutex.
  static void fold_waiting(Film& f, const FrameLayout& frame);
  // The frame's film, or null when none is kept. Takes mutex_.
  std::shared_ptr<Film> film_of(const std::string& job_id, int frame);
  std::mutex mutex_;
  std::map<std::pair<std::string, int>, std::shared_ptr<Film>> films_;  // by job and frame
};

}  // namespace farm
