#pragma once
// Finished batches of tiles on disk: <dir>/<job id>/<part>, each a serialized
// farm.v1.RenderTileResponse (the worker's TileData for the batch's rect, and its TileStats); the
// part is the batch's first tile index (JobStore's tiles.part). Written to a temporary file and
// renamed into place, so a file under a part's name is always complete; the scheduler writes it
// BEFORE it marks the tiles done in the job store, so done tiles' data survives a crash.
//
// A file is a header and the payload:
//   "FARMTIL1"                       8 bytes, the format
//   payload length                   8 bytes, little endian
//   SHA-256 of the payload           64 lowercase hex digits
//   payload                          the serialized RenderTileResponse
// so that a file cut short, emptied, deleted or with bytes changed on disk is found when it is read
// back, and its tiles rendered again instead of merged (protobuf parses most damaged bytes
// without complaint: a flipped byte in pixel data is just another pixel).
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "proto/farm.pb.h"

namespace farm {

// A result file that cannot be trusted: missing, unreadable, cut short, or failing its checksum.
// what() names the file and the problem.
class DamagedTileResult : public std::runtime_error {
 public:
  DamagedTileResult(std::filesystem::path file, const std::string& message)
      : std::runtime_error(message), file_(std::move(file)) {}
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

class TileResults {
 public:
  explicit TileResults(std::filesystem::path dir);  // creates dir

  // DiskFull (naming the folder) when the disk has no room for it; nothing is left behind.
  void write(const std::string& job_id, std::uint32_t part, const v1::RenderTileResponse& tile) const;
  // DamagedTileResult when the file is missing, unreadable, truncated or fails its checksum.
  v1::RenderTileResponse read(const std::string& job_id, std::uint32_t part) const;
  std::uintmax_t remove_job(const std::string& job_id) const;  // returns the bytes freed
  void remove(const std::string& job_id, std::uint32_t part) const;  // nothing if it is absent

  std::filesystem::path path_of(const std::string& job_id, std::uint32_t part) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace farm
