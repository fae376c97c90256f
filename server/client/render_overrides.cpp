#include "server/client/render_overrides.h"

#include <fmt/format.h>

#include <tuple>

#include "renderer/job/video_format.h"
#include "renderer/util/input_error.h"

namespace farm {

void apply_overrides(Job& job, const RenderOverrides& o) {
  RenderSettings& r = job.render;
  if (o.engine) {
    const auto engine = engine_from_string(*o.engine);
    if (!engine) throw InputError(fmt::format("--engine: unknown engine '{}'", *o.engine));
    r.engine = *engine;
  }
  if (o.width) r.width = *o.width;
  if (o.height) r.height = *o.height;
  if (o.spp) r.spp = *o.spp;
  if (o.threads) r.threads = *o.threads;
  if (o.tile_size) r.tile_size = *o.tile_size;
  if (o.max_depth) r.max_depth = *o.max_depth;
  if (o.seed) r.seed = *o.seed;
  for (const std::string& name : o.add_aovs) {
    const auto aov = aov_from_string(name);
    if (!aov) throw InputError(fmt::format("unknown AOV '{}'", name));
    r.aovs.add(*aov);
  }
  if (o.image) job.output.image = *o.image;
  if (o.preview) job.output.preview = *o.preview;
  if (o.video) {
    job.output.video = *o.video;
    if (!o.video->empty() && !video_format_of(*o.video)) {
      throw InputError(fmt::format("--video {}: cannot make videos of type '{}' (expected {}, or none)",
                                   o.video->string(), o.video->extension().string(), video_extensions()));
    }
    if (!o.video->empty() && !job.frames) {
      throw InputError(fmt::format("--video {}: the job renders one still; a video needs a frame range",
                                   o.video->string()));
    }
  }
  if (!job.output.video.empty() && job.output.preview.empty()) {
    throw InputError(fmt::format("--preview none: the video {} is made from the frames' previews (give --video "
                                 "none too, to render without it)",
                                 job.output.video.string()));
  }
  if (!job.frames) {
    job.output_patterns = job.output;  // a still's names are its patterns
    if (o.frames) {
      throw InputError(fmt::format("--frames {}-{}: the job renders one still; give it a range, such as "
                                   "\"frames\": {{\"start\": 1, \"end\": 48}}",
                                   o.frames->first, o.frames->second));
    }
    return;
  }
  // A job with frames: the outputs are patterns, and the job is re-evaluated at its first frame.
  for (const auto& [given, pattern, option] :
       {std::tuple{o.image, &job.output_patterns.image, "--out"}, std::tuple{o.preview, &job.output_patterns.preview, "--preview"}}) {
    if (!given) continue;
    if (!given->empty() && !has_frame_pattern(given->string())) {
      throw InputError(fmt::format("{} {}: the job renders frames, one file each: give a '#' run for the frame "
                                   "number (for example {}.####{})",
                                   option, given->string(), (given->parent_path() / given->stem()).string(),
                                   given->extension().string()));
    }
    *pattern = *given;
  }
  if (o.frames) {
    FrameRange picked = *job.frames;
    picked.only = *o.frames;
    if (o.frames->first < job.frames->start || o.frames->second > job.frames->end || picked.frames().empty()) {
      throw InputError(fmt::format("--frames {}-{}: the job's frames are {} to {} by {}", o.frames->first,
                                   o.frames->second, job.frames->start, job.frames->end, job.frames->step));
    }
    job.frames = picked;
  }
  job = job_at_frame(job, job.frames->frames().front());
}

}  // namespace farm
