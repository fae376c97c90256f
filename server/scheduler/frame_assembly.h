#pragma once
// Where a job's finished batches of tiles wait for the merge, and how they become its frame.
//
// - TileFileAssembly (the farm): each batch is a file (TileResults) written before its tiles are
//   marked done, so a restarted scheduler merges what an earlier process rendered.
// - InMemoryAssembly (the embedded farm of `farm render`): each batch is pasted into the job's
//   film as it arrives. Nothing is encoded, written, read back or decoded; nothing survives the
//   process, which `farm render` does not need (its job store lives in memory too).
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/image/tile_buffer.h"
#include "server/scheduler/tile_results.h"
#include "server/scheduler/tile_worker.h"

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
};

class FrameAssembly {
 public:
  virtual ~FrameAssembly() = default;
  // Keeps one batch (the part is its first tile index). Throws when it cannot: the batch is
  // then not marked done.
  virtual void add(const std::string& job_id, const FrameLayout& frame, std::uint32_t part,
                   RenderedTiles& tiles) = 0;
  // The job's frame from its parts (each once, as the job store lists them), with the render
  // statistics summed. DamagedParts (every such part, once all are read) when parts' kept data
  // is damaged; std::runtime_error when a part was never kept or does not fit.
  virtual TileBuffer assemble(const std::string& job_id, const FrameLayout& frame,
                              const std::vector<std::uint32_t>& parts) = 0;
  // Forgets the job (done, failed or cancelled).
  virtual void remove_job(const std::string& job_id) = 0;
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
  void add(const std::string& job_id, const FrameLayout& frame, std::uint32_t part,
           RenderedTiles& tiles) override;
  TileBuffer assemble(const std::string& job_id, const FrameLayout& frame,
                      const std::vector<std::uint32_t>& parts) override;
  void remove_job(const std::string& job_id) override { files_.remove_job(job_id); }
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
  TileResults files_;
};

class InMemoryAssembly final : public FrameAssembly {
 public:
  void add(const std::string& job_id, const FrameLayout& frame, std::uint32_t part,
           RenderedTiles& tiles) override;
  TileBuffer assemble(const std::string& job_id, const FrameLayout& frame,
                      const std::vector<std::uint32_t>& parts) override;
  void remove_job(const std::string& job_id) override;
  void frame_merged(const std::string& job_id, int frame) override;  // its film goes
  void discard(const std::string& job_id, std::uint32_t part) override;
  void free_parts(const std::string& job_id, const std::vector<std::uint32_t>& parts) override {
    for (std::uint32_t part : parts) discard(job_id, part);
  }

 private:
  struct Film {
    std::mutex mutex;  // guards parts; pastes are of disjoint rects
    TileBuffer film;
    // Pasted so far, in order, with their statistics. A part discarded and pasted again is
    // listed twice until the older one is discarded: the newer pixels are the ones in the film.
    std::vector<std::pair<std::uint32_t, RenderStats>> parts;
  };
  std::mutex mutex_;
  std::map<std::pair<std::string, int>, std::shared_ptr<Film>> films_;  // by job and frame
};

}  // namespace farm
