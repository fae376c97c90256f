#pragma once
// A job's frames (jobs/README.md, "frames"): start .. end by step, played at fps, of which
// `only` may pick a sub-range (what `farm render --frames 10-20` writes). Output names carry the
// frame number in their last run of '#' (out/turntable.####.exr, as Blender and Deadline do).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace farm {

// Frame numbers a job may use, and how many one job may render: every frame is a set of work
// units the scheduler keeps, so a range is bounded like every other size.
inline constexpr int kMaxFrameNumber = 9'999'999;
inline constexpr int kMaxFramesPerJob = 10'000;

struct FrameRange {
  int start = 1;
  int end = 1;
  int step = 1;
  double fps = 24.0;
  std::optional<std::pair<int, int>> only;  // first, last: inclusive, within start .. end

  // The frames rendered, ascending: start, start + step, ... <= end, inside `only` when given.
  std::vector<int> frames() const;
  // Whether `frame` is one of frames(), without listing them.
  bool contains(int frame) const;
  // Seconds from the range's start: (frame - start) / fps, what glTF animations play at.
  double seconds_at(int frame) const { return (frame - start) / fps; }
};

// "10-20" or "5": the frames `--frames` picks. nullopt when `text` is neither (or 20-10).
std::optional<std::pair<int, int>> parse_frame_pick(std::string_view text);

// Whether `file_name` has a run of '#' for the frame number.
bool has_frame_pattern(std::string_view file_name);
// `pattern` with its last run of '#' replaced by `frame`, zero-padded to the run's length (more
// digits when the number needs them): ("out/t.####.exr", 7) -> "out/t.0007.exr".
std::string frame_file_name(std::string_view pattern, int frame);

}  // namespace farm
