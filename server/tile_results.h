#pragma once
// Finished tiles on disk: <dir>/<job id>/<tile index>, each a serialized farm.v1.TileResult
// (the worker's TileData and TileStats). Written to a temporary file and renamed into place, so a
// file under a tile's name is always complete; the scheduler writes it BEFORE it marks the tile
// done in the job store, so a done tile's data survives a crash.
#include <cstdint>
#include <filesystem>
#include <string>

#include "proto/farm.pb.h"

namespace farm {

class TileResults {
 public:
  explicit TileResults(std::filesystem::path dir);  // creates dir

  void write(const std::string& job_id, std::uint32_t index, const v1::RenderTileResponse& tile) const;
  // std::runtime_error when the file is missing or unreadable.
  v1::RenderTileResponse read(const std::string& job_id, std::uint32_t index) const;
  bool has(const std::string& job_id, std::uint32_t index) const;
  void remove_job(const std::string& job_id) const;

  std::filesystem::path path_of(const std::string& job_id, std::uint32_t index) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace farm
