#pragma once
// A job's video (jobs/README.md, output.video): once every frame is merged, the frames' previews
// are encoded by ffmpeg, Debian's package run as a program (no shell; its libraries would tie
// the farm to their ABI for one feature), in frame order at the job's fps. The farm finds
// ffmpeg when a job asks for a video, at submit (find_ffmpeg), so that a machine without it
// refuses the job before rendering rather than failing it at the end.
#include <chrono>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace farm {

// Where ffmpeg is: the program FARM_FFMPEG names when that is set (a test points it elsewhere),
// else the first executable `ffmpeg` on PATH.
struct FfmpegLookup {
  std::filesystem::path program;  // empty: none
  std::string problem;            // why there is none, for a message a person can act on
  explicit operator bool() const { return !program.empty(); }
};
FfmpegLookup find_ffmpeg();

struct VideoRequest {
  std::vector<std::filesystem::path> frames;  // the previews (PNG or JPEG, one type), in frame order
  double fps = 24.0;
  std::filesystem::path output;  // its extension picks the format (renderer/job/video_format.h)
  // ffmpeg is killed past this: a video is a few seconds of ffmpeg for frames the farm took far
  // longer to render, so this only keeps a wedged ffmpeg from holding the job for ever.
  std::chrono::milliseconds timeout = std::chrono::minutes(10);
  // Asked every tenth of a second while ffmpeg runs: true kills it (the scheduler is stopping)
  // and encode_video throws VideoStopped. None: never.
  std::function<bool()> stop_requested;
};

// ffmpeg was killed because request.stop_requested said so; nothing was written.
struct VideoStopped : std::runtime_error {
  VideoStopped() : std::runtime_error("the video was not made: the scheduler is stopping") {}
};

// Encodes the frames into request.output, written under a temporary name beside it and renamed,
// so that the file is either the whole video or absent. Frames of odd width or height get one
// black column or row: H.264 in yuv420p needs even sizes. std::runtime_error carrying ffmpeg's
// own message when there is no ffmpeg, when it fails, or when it runs past the timeout;
// VideoStopped when stopped.
void encode_video(const VideoRequest& request);

}  // namespace farm
