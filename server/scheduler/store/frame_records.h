#pragma once
// The job store's frames (job_store.h): which of a job's frames have every unit done, the parts
// that hold them pass by pass, how many passes are complete, and which frames are merged.
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.pb.h"
#include "server/scheduler/store/store_part.h"

namespace farm {

class FrameRecords : public StorePart {
 public:
  explicit FrameRecords(StoreSession& session) : StorePart(session) {}

  // Frames. The job's frames whose tiles are all done and which are not merged yet: `frame`
  // alone when given (after one of its batches was done), else every such frame (a restart).
  std::vector<int> complete_frames(const std::string& job_id, std::optional<int> frame = std::nullopt) const;
  // The parts (TileResults) that hold the frame's done tiles of passes 0 .. passes - 1, in pass
  // order (then by part).
  std::vector<FramePart> frame_parts(const std::string& job_id, int frame, int passes) const;
  // How many of the frame's sample passes are done from the first on: p when every tile of
  // passes 0 .. p - 1 is done and one of pass p is not (the job's passes when all are; 0 for an
  // unknown job). A frame's progressive preview shows these.
  int complete_passes(const std::string& job_id, int frame) const;
  // The frame is merged and its files written: counted in frames_done, if the job is active and
  // the frame's tiles are all still done (false otherwise: a quarantine took some back, and the
  // frame is merged again once they are rendered again). A part taken back later (quarantine,
  // damage, room for other jobs) makes its frame unmerged again.
  bool frame_merged(const std::string& job_id, int frame);
  // Whether the frame of the job is merged (its files can be fetched).
  bool is_frame_merged(const std::string& job_id, int frame) const;
};

}  // namespace farm
