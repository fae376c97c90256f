#include "server/common/video_encoder.h"

#include <fmt/format.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "renderer/job/video_format.h"
#include "renderer/util/atomic_file.h"
#include "server/common/child_process.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

// At most this much of ffmpeg's output goes into a message: its last lines say what went wrong.
constexpr std::size_t kMaxMessageBytes = 2000;

bool is_executable_file(const fs::path& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
}

// A folder of our own under the temp dir, removed with everything in it.
class TempFolder {
 public:
  TempFolder() {
    std::string name = (fs::temp_directory_path() / "farm-video-XXXXXX").string();
    if (!::mkdtemp(name.data())) {
      throw std::runtime_error(fmt::format("cannot make a temporary folder: {}", std::strerror(errno)));
    }
    path_ = name;
  }
  ~TempFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// ffmpeg's image2 input reads '%' as the start of a pattern; "%%" is a literal one.
std::string escaped_for_pattern(const std::string& s) {
  std::string out;
  for (char c : s) {
    out += c;
    if (c == '%') out += '%';
  }
  return out;
}

// The tail of ffmpeg's output, on one line.
std::string last_words(const std::string& output) {
  std::string_view s = output;
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  if (s.size() > kMaxMessageBytes) s = s.substr(s.size() - kMaxMessageBytes);
  std::string out;
  for (char c : s) {
    if (c == '\n') {
      out += "; ";
    } else if (c != '\r') {
      out += c;
    }
  }
  return out.empty() ? "(it said nothing)" : out;
}

// The encoder and muxer arguments of each format: quality over size (a preview is 8-bit sRGB
// already; crf 18 keeps it visually lossless), and an mp4 playable while it downloads.
std::vector<std::string> format_arguments(VideoFormat format) {
  switch (format) {
    case VideoFormat::Mp4:
      return {"-c:v", "libx264", "-crf", "18", "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4"};
    case VideoFormat::Matroska:
      return {"-c:v", "libx264", "-crf", "18", "-pix_fmt", "yuv420p", "-f", "matroska"};
    case VideoFormat::WebM:
      return {"-c:v", "libvpx-vp9", "-crf", "31", "-b:v", "0", "-row-mt", "1", "-pix_fmt", "yuv420p", "-f", "webm"};
  }
  throw std::logic_error("unknown video format");
}

}  // namespace

FfmpegLookup find_ffmpeg() {
  if (const char* named = std::getenv("FARM_FFMPEG"); named && *named) {
    if (is_executable_file(named)) return {fs::absolute(named), {}};
    return {{}, fmt::format("FARM_FFMPEG={} is not an executable program", named)};
  }
  const char* path = std::getenv("PATH");
  std::string_view dirs = path ? path : "";
  while (!dirs.empty()) {
    const std::size_t colon = dirs.find(':');
    const std::string_view dir = dirs.substr(0, colon);
    dirs.remove_prefix(colon == std::string_view::npos ? dirs.size() : colon + 1);
    if (dir.empty()) continue;  // the working directory: never where a server's programs come from
    const fs::path candidate = fs::path(dir) / "ffmpeg";
    if (is_executable_file(candidate)) return {fs::absolute(candidate), {}};
  }
  return {{}, "there is no ffmpeg on PATH (install Debian's ffmpeg package, as deploy/install-deps.sh does)"};
}

void encode_video(const VideoRequest& request) {
  const std::optional<VideoFormat> format = video_format_of(request.output);
  if (!format) {
    throw std::runtime_error(fmt::format("{}: not a video file name (expected {})", request.output.string(),
                                         video_extensions()));
  }
  if (request.frames.empty()) throw std::runtime_error("no frames to encode");
  const FfmpegLookup ffmpeg = find_ffmpeg();
  if (!ffmpeg) throw std::runtime_error(ffmpeg.problem);

  // The frames as links 000000.png, 000001.png, ... in a folder of our own: ffmpeg's pattern
  // parser sees only these names, never the frames' own (whose '%' or '#' would mean something).
  const TempFolder links;
  const std::string ext = request.frames.front().extension().string();
  for (std::size_t i = 0; i < request.frames.size(); ++i) {
    const fs::path& frame = request.frames[i];
    if (frame.extension() != ext) {
      throw std::runtime_error(fmt::format("the frames' previews are not all of one type ({} and {})",
                                           request.frames.front().string(), frame.string()));
    }
    std::error_code ec;
    if (!fs::is_regular_file(frame, ec)) {
      throw std::runtime_error(fmt::format("the preview of frame {} of the video, {}, is missing", i + 1,
                                           frame.string()));
    }
    fs::create_symlink(fs::absolute(frame), links.path() / fmt::format("{:06}{}", i, ext));
  }

  const fs::path output = fs::absolute(request.output);
  // Written beside the output under a dot name (kept out of result listings while ffmpeg writes
  // it) and renamed over it once ffmpeg succeeded; removed on every failure.
  write_file_atomically(output, [&](const fs::path& temp) {
    std::vector<std::string> argv = {
        ffmpeg.program.string(), "-nostdin", "-hide_banner", "-loglevel", "error", "-y",
        "-framerate", fmt::format("{}", request.fps), "-start_number", "0",
        "-i", escaped_for_pattern(links.path().string()) + "/%06d" + ext,
        "-frames:v", std::to_string(request.frames.size()),
        // Odd sizes padded (never scaled) to even ones with a black column or row.
        "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"};
    for (std::string& a : format_arguments(*format)) argv.push_back(std::move(a));
    argv.push_back(temp.string());

    std::optional<int> code;
    std::string said;
    bool stopped = false;
    {
      ChildProcess child(argv);
      const auto deadline = std::chrono::steady_clock::now() + request.timeout;
      constexpr auto kLook = std::chrono::milliseconds(100);  // how often stop_requested is asked
      while (!code && std::chrono::steady_clock::now() < deadline) {
        if (request.stop_requested && request.stop_requested()) {
          stopped = true;
          break;
        }
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
        code = child.wait_exit(std::clamp(left, std::chrono::milliseconds(0), std::chrono::milliseconds(kLook)));
      }
      if (!code) {
        child.send_signal(SIGKILL);
        child.wait_exit(std::chrono::seconds(10));
      }
      said = child.output_to_end(std::chrono::seconds(2));
    }
    if (stopped) throw VideoStopped();
    if (!code) {
      throw std::runtime_error(fmt::format("ffmpeg ran for more than {} s and was stopped: {}",
                                           request.timeout.count() / 1000, last_words(said)));
    }
    if (*code != 0) {
      throw std::runtime_error(fmt::format("ffmpeg failed (exit code {}): {}", *code, last_words(said)));
    }
  });
}

}  // namespace farm
