#pragma once
// The videos a job can ask for (jobs/README.md, output.video): the container is picked by the
// file's extension, and with it the codec ffmpeg is asked to encode the frames' previews with.
#include <filesystem>
#include <optional>
#include <string_view>

namespace farm {

enum class VideoFormat {
  Mp4,       // .mp4: H.264, yuv420p (what every player and browser plays)
  Matroska,  // .mkv: H.264, yuv420p
  WebM,      // .webm: VP9, yuv420p
};

// The format `file` names by its extension (lower or upper case); nullopt for any other.
std::optional<VideoFormat> video_format_of(const std::filesystem::path& file);
// The extensions video_format_of accepts, for messages: ".mp4, .mkv or .webm".
std::string_view video_extensions();
// "H.264" or "VP9": what the format's frames are encoded with.
std::string_view video_codec_name(VideoFormat format);

}  // namespace farm
