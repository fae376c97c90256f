#include "renderer/job/video_format.h"

#include <string>

#include "renderer/util/file_extension.h"

namespace farm {

std::optional<VideoFormat> video_format_of(const std::filesystem::path& file) {
  const std::string ext = lowercase_extension(file);
  if (ext == ".mp4") return VideoFormat::Mp4;
  if (ext == ".mkv") return VideoFormat::Matroska;
  if (ext == ".webm") return VideoFormat::WebM;
  return std::nullopt;
}

std::string_view video_extensions() { return ".mp4, .mkv or .webm"; }

std::string_view video_codec_name(VideoFormat format) { return format == VideoFormat::WebM ? "VP9" : "H.264"; }

}  // namespace farm
