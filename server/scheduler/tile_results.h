#pragma once
// Finished batches of tiles on disk: <dir>/<job id>/<part>, each a serialized
// farm.v1.RenderTileResponse (the worker's TileData for the batch's rect, and its TileStats); the
// part is the batch's first tile index (JobStore's tiles.part). Written to a temporary file and
// renamed into place, so a file under a part's name is always complete; the scheduler writes it
// BEFORE it marks the tiles done in the job store, so done tiles' data survives a crash.
#include <cstdint>
#include <filesystem>
#include <string>

#include "proto/farm.pb.h"

namespace farm {

class TileResults {
 public:
  explicit TileResults(std::filesystem::path dir);  // creates dir

  void write(const std::string& job_id, std::uint32_t part, const v1::RenderTileResponse& tile) const;
  // std::runtime_error when the file is missing or unreadable.
  v1::RenderTileResponse read(const std::string& job_id, std::uint32_t part) const;
  void remove_job(const std::string& job_id) const;

  std::filesystem::path path_of(const std::string& job_id, std::uint32_t part) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace farm
