// The job file's whole format is checked here, key by key, so that a reader sees every rule and
// its error message side by side with jobs/README.md; the rules a keyframed value meets at a frame
// too are in job_checks.h.
#include "renderer/job/job.h"

#include <fmt/format.h>

#include <cerrno>
#include <fstream>
#include <glm/vec3.hpp>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <system_error>

#include "renderer/job/job_animation.h"
#include "renderer/job/job_checks.h"
#include "renderer/job/job_limits.h"
#include "renderer/job/video_format.h"
#include "renderer/util/confined_file.h"
#include "renderer/util/input_error.h"
#include "renderer/util/json_reader.h"
#include "renderer/util/path_confinement.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMaxShownText = 64;

struct Context {
  fs::path job_dir;     // absolute
  fs::path job_file;    // in job_dir with its symlinks resolved: what model paths are relative to
  fs::path asset_root;  // absolute, symlinks resolved
  std::string asset_root_hint;  // JobLoadOptions'
  bool models_by_name = false;  // JobLoadOptions'
  // Each file name's confinement, worked out once a parse: a scene places one model file under
  // many objects, and confine_file walks the name's folders with a syscall apiece. A job of 10,000
  // cows spent 55% of `farm render`'s set-up there (perf): 191-261 ms of set-up, 90-112 after.
  mutable std::map<std::string, ConfinedFile> confined;
};

// An animated job's values are checked at every frame when it is loaded, so that no frame fails
// halfway through a render: at most this many keyframed values over all its frames.
constexpr std::size_t kMaxAnimatedValueChecks = 10'000'000;

// A user's string inside a message: shortened so a hostile value cannot flood logs.
std::string shown(const std::string& s) {
  if (s.size() <= kMaxShownText) return s;
  return s.substr(0, kMaxShownText) + "...";
}

// A file the job names (a model, an environment map), confined to the asset root.
fs::path resolve_named_file(const JsonValue& v, const Context& ctx) {
  const std::string written = v.string();
  if (written.empty()) v.fail("expected a file path, got an empty string");
  if (ctx.models_by_name) {
    // As the job will be laid out: under the root by the name it gives, an absolute path being
    // one of the client's machine, which no farm lays out.
    const fs::path named = (ctx.asset_root / written).lexically_normal();
    if (written.find('\0') != std::string::npos) v.fail(fmt::format("'{}' contains a NUL character", shown(written)));
    if (fs::path(written).has_root_path() || !lies_within(ctx.asset_root, named)) {
      v.fail(fmt::format("'{}' lies outside the asset root ({})", shown(written), ctx.asset_root.string()));
    }
    return named;
  }
  // A person writes a job on their own machine: an absolute path is fine if it lies in the root
  // (a submission rewrites it relative to the root before it travels).
  auto [known, fresh] = ctx.confined.try_emplace(written);
  if (fresh) known->second = confine_file(ctx.asset_root, ctx.job_file, written, ReferenceForm::relative_or_absolute);
  const ConfinedFile& file = known->second;
  if (file.verdict == Confinement::missing) v.fail(fmt::format("no such file '{}'", shown(written)));
  if (!file.allowed()) {
    v.fail(file.verdict == Confinement::outside && !ctx.asset_root_hint.empty()
               ? fmt::format("{}; {}", file.reason, ctx.asset_root_hint)
               : file.reason);
  }
  return file.resolved;
}

MaterialOverride parse_material(const JsonValue& v) {
  const JsonObject obj = v.object(
      {"ambient", "diffuse", "specular", "emission", "shininess", "ior", "transmission",
       "emission_sides"});
  MaterialOverride m;
  if (auto x = obj.get("ambient")) m.ambient = x->vec3(kRadiometric);
  if (auto x = obj.get("diffuse")) m.diffuse = x->vec3(kRadiometric);
  if (auto x = obj.get("specular")) m.specular = x->vec3(kRadiometric);
  if (auto x = obj.get("emission")) m.emission = x->vec3(kRadiometric);
  if (auto x = obj.get("shininess")) m.shininess = x->real(kShininessRange);
  if (auto x = obj.get("ior")) m.ior = x->real(kIorRange);
  if (auto x = obj.get("transmission")) m.transmission = x->real(kTransmissionRange);
  if (auto x = obj.get("emission_sides")) {
    const std::string s = x->string();
    const auto sides = emission_sides_from_string(s);
    if (!sides) x->fail(fmt::format("unknown emission_sides '{}' (expected front or both)", shown(s)));
    m.emission_sides = *sides;
  }
  return m;
}

JobObject parse_object(const JsonValue& v, const Context& ctx) {
  const JsonObject obj = v.object({"file", "translate", "rotate", "scale", "material", "animation"});
  JobObject o;
  const JsonValue file = obj.require("file");
  o.file = resolve_named_file(file, ctx);
  o.file_as_written = file.string();
  if (auto x = obj.get("translate")) o.transform.translate = x->vec3();
  if (auto x = obj.get("rotate")) {
    const JsonObject rot = x->object({"axis", "degrees"});
    if (auto axis = rot.get("axis")) o.transform.rotate_axis = unit_axis(axis->vec3(), axis->place());
    if (auto deg = rot.get("degrees")) o.transform.rotate_degrees = deg->real();
  }
  if (auto x = obj.get("scale")) {
    o.transform.scale = x->vec3();
    check_scale(o.transform.scale, x->place());
  }
  if (auto x = obj.get("material")) o.material = parse_material(*x);
  if (auto x = obj.get("animation")) {
    // A name, an index, or false; the model, not loaded here, is checked when the scene is built.
    if (x->raw().is_boolean()) {
      if (x->boolean()) x->fail("expected an animation's name or index, or false (true is the default)");
      o.animation.pick = ObjectAnimation::Pick::Off;
    } else if (x->raw().is_string()) {
      o.animation.pick = ObjectAnimation::Pick::Name;
      o.animation.name = x->string();
    } else if (x->raw().is_number()) {
      o.animation.pick = ObjectAnimation::Pick::Index;
      o.animation.index = static_cast<std::size_t>(x->integer(0, 1'000'000));
    } else {
      x->fail_expected("an animation's name or index, or false");
    }
  }
  return o;
}

Camera parse_camera(const JsonValue& v) {
  const JsonObject obj =
      v.object({"position", "target", "up", "fov_y", "near", "far", "aspect"});
  Camera cam;
  if (auto x = obj.get("position")) cam.position = x->vec3();
  if (auto x = obj.get("target")) cam.target = x->vec3();
  const auto up = obj.get("up");
  if (up) cam.up = up->vec3();
  if (auto x = obj.get("fov_y")) cam.fov_y_degrees = x->real(kFovYRange);
  const auto near = obj.get("near");
  if (near) cam.near = near->real(kCameraPositive);
  const auto far = obj.get("far");
  if (far) cam.far = far->real(kCameraPositive);
  if (auto x = obj.get("aspect")) cam.aspect = x->real(kCameraPositive);
  check_camera(cam, {near.has_value(), far.has_value(), up.has_value()}, v.place());
  return cam;
}

glm::vec3 parse_intensity(const JsonValue& v) {
  if (v.raw().is_array()) return v.vec3(kRadiometric);
  if (!v.raw().is_number()) v.fail_expected("a number or 3 numbers");
  return glm::vec3(v.real(kRadiometric));
}

std::vector<Light> parse_lights(const JsonValue& v) {
  std::vector<Light> lights;
  for (const JsonValue& item : v.array()) {
    const JsonObject obj = item.object({"position", "intensity"});
    Light light;
    light.kind = Light::Kind::Point;
    light.position = obj.require("position").vec3();
    if (auto x = obj.get("intensity")) light.intensity = parse_intensity(*x);
    lights.push_back(light);
  }
  return lights;
}

// Degrees of a turn: any number of whole turns, within reason.
const NumberRange kRotationDegrees = NumberRange::between(-36000.0, 36000.0);

JobEnvironment parse_environment(const JsonValue& v, const Context& ctx) {
  const JsonObject obj = v.object({"map", "radiance", "intensity", "rotate_degrees"});
  JobEnvironment e;
  if (auto x = obj.get("map")) {
    e.map = resolve_named_file(*x, ctx);
    e.map_as_written = x->string();
  }
  if (auto x = obj.get("radiance")) e.radiance = parse_intensity(*x);
  if (auto x = obj.get("intensity")) e.intensity = x->real(kRadiometric);
  if (auto x = obj.get("rotate_degrees")) e.rotate_degrees = x->real(kRotationDegrees);
  return e;
}

JobScene parse_scene(const JsonValue& v, const Context& ctx) {
  const JsonObject obj = v.object({"objects", "camera", "lights", "ambient", "background", "environment"});
  JobScene scene;
  const JsonValue objects = obj.require("objects");
  const std::vector<JsonValue> items = objects.array();
  if (items.empty()) objects.fail("expected at least one object, got an empty array");
  for (const JsonValue& item : items) scene.objects.push_back(parse_object(item, ctx));
  if (auto x = obj.get("camera")) scene.camera = parse_camera(*x);
  if (auto x = obj.get("lights")) scene.lights = parse_lights(*x);
  if (auto x = obj.get("ambient")) scene.ambient = x->vec3(kRadiometric);
  if (auto x = obj.get("background")) scene.background = x->vec3(kRadiometric);
  if (auto x = obj.get("environment")) {
    // One light from all around: a constant background or ambient beside it would contradict it.
    for (const char* replaced : {"background", "ambient"}) {
      if (obj.get(replaced)) {
        x->fail(fmt::format("an environment stands for scene.{} too: give one or the other", replaced));
      }
    }
    scene.environment = parse_environment(*x, ctx);
  }
  return scene;
}

template <typename Enum, std::size_t N>
std::string names_of(const Enum (&values)[N]) {
  std::vector<std::string_view> names;
  for (Enum e : values) names.push_back(to_string(e));
  return join_alternatives(names);
}

constexpr AccelKind kAccels[] = {AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Naive,
                                 AccelKind::Embree};

void parse_render(const JsonValue& v, RenderSettings& r) {
  const JsonObject obj = v.object({"engine", "width", "height", "spp", "pass_spp", "max_depth", "seed",
                                   "tile_size", "threads", "accel", "shadows", "light_sampling"});
  constexpr int kIntMax = std::numeric_limits<int>::max();
  if (auto x = obj.get("engine")) {
    const std::string s = x->string();
    const auto e = engine_from_string(s);
    if (!e) x->fail(fmt::format("unknown engine '{}' (expected {})", shown(s), join_alternatives({kEngineNames.begin(), kEngineNames.end()})));
    r.engine = *e;
  }
  if (auto x = obj.get("width")) r.width = x->int32(1, kMaxImageSide);
  if (auto x = obj.get("height")) r.height = x->int32(1, kMaxImageSide);
  if (auto x = obj.get("spp")) r.spp = x->int32(1, kMaxSpp);
  // 0 (the default) renders a frame's samples in one pass; raster and whitted ignore it.
  if (auto x = obj.get("pass_spp")) r.pass_spp = x->int32(0, kMaxSpp);
  if (auto x = obj.get("max_depth")) r.max_depth = x->int32(-1, kIntMax);
  if (auto x = obj.get("seed")) r.seed = x->unsigned_integer();
  if (auto x = obj.get("tile_size")) r.tile_size = x->int32(1, kMaxTileSize);
  if (auto x = obj.get("threads")) r.threads = x->int32(0, kMaxThreads);
  if (auto x = obj.get("accel")) {
    const std::string s = x->string();
    const auto a = accel_from_string(s);
    if (!a) x->fail(fmt::format("unknown accel '{}' (expected {})", shown(s), names_of(kAccels)));
    r.accel = *a;
  }
  if (auto x = obj.get("shadows")) r.shadows = x->boolean();
  if (auto x = obj.get("light_sampling")) {
    const std::string s = x->string();
    const auto l = light_sampling_from_string(s);
    if (!l) x->fail(fmt::format("unknown light_sampling '{}' (expected nee-mis or bsdf)", shown(s)));
    r.light_sampling = *l;
  }
}

FrameRange parse_frames(const JsonValue& v) {
  const JsonObject obj = v.object({"start", "end", "step", "fps", "only"});
  FrameRange r;
  const JsonValue start = obj.require("start");
  r.start = start.int32(0, kMaxFrameNumber);
  const JsonValue end = obj.require("end");
  r.end = end.int32(0, kMaxFrameNumber);
  if (r.end < r.start) end.fail(fmt::format("expected an end >= start ({}), got {}", r.start, r.end));
  if (auto x = obj.get("step")) r.step = x->int32(1, kMaxFrameNumber);
  if (auto x = obj.get("fps")) r.fps = x->real(NumberRange{0.0, 1000.0, true, false});
  if (auto x = obj.get("only")) {
    const std::vector<JsonValue> pair = x->array();
    if (pair.size() != 2) x->fail(fmt::format("expected [first, last], got an array of {}", pair.size()));
    const int first = pair[0].int32(r.start, r.end);
    const int last = pair[1].int32(first, r.end);
    r.only = std::pair{first, last};
    if (r.frames().empty()) {
      x->fail(fmt::format("frames {}-{} pick no frame of {}-{} step {}", first, last, r.start, r.end, r.step));
    }
  }
  const std::size_t count = static_cast<std::size_t>((r.end - r.start) / r.step) + 1;
  if (count > static_cast<std::size_t>(kMaxFramesPerJob)) {
    v.fail(fmt::format("{} frames; a job renders at most {}", count, kMaxFramesPerJob));
  }
  return r;
}

// With a frame range every output names its frame: a '#' run for the number.
void check_frame_pattern(const std::optional<JsonValue>& written, const fs::path& file, const JsonValue& output) {
  if (file.empty() || has_frame_pattern(file.string())) return;
  const JsonValue at = written ? *written : output;
  at.fail(fmt::format("'{}' has no '#' for the frame number: a job with frames writes one file a frame "
                      "(for example out/{}.####{})",
                      shown(file.string()), file.stem().string(), file.extension().string()));
}

// output.video: a file ffmpeg is asked to make from the frames' previews, once they are all done.
void parse_video(const JsonValue& v, Job& job) {
  job.output.video = v.string();
  const fs::path& video = job.output.video;
  if (video.empty()) v.fail("expected a file path, got an empty string");
  if (!video_format_of(video)) {
    v.fail(fmt::format("'{}': cannot make videos of type '{}' (expected {})", shown(video.string()),
                       shown(video.extension().string()), video_extensions()));
  }
  if (!job.frames) {
    v.fail("a video needs a frame range: give \"frames\": {\"start\": 1, \"end\": 48}");
  }
  if (job.output.preview.empty()) {
    v.fail("a video is made from the frames' previews, and output.preview is \"\" (none): give the "
           "previews a name, such as out/name.####.png");
  }
  for (const fs::path& other : {job.output.image, job.output.preview}) {
    if (video.lexically_normal() == other.lexically_normal()) {
      v.fail(fmt::format("'{}' is also the name of output.{}", shown(video.string()),
                         other == job.output.image ? "image" : "preview"));
    }
  }
}

void parse_output(const JsonValue& v, Job& job) {
  const JsonObject obj = v.object({"image", "preview", "aovs", "video"});
  const auto image = obj.get("image");
  if (image) {
    job.output.image = image->string();
    if (job.output.image.empty()) image->fail("expected a file path, got an empty string");
  }
  const auto preview = obj.get("preview");
  if (preview) job.output.preview = preview->string();  // "" = no preview
  if (auto x = obj.get("aovs")) {
    for (const JsonValue& item : x->array()) {
      const std::string s = item.string();
      const auto aov = aov_from_string(s);
      if (!aov) item.fail(fmt::format("unknown AOV '{}' (expected {})", shown(s), names_of(kAllAovs)));
      if (job.render.aovs.has(*aov)) item.fail(fmt::format("duplicate AOV '{}'", s));
      job.render.aovs.add(*aov);
    }
  }
  if (!job.output.preview.empty() &&
      job.output.image.lexically_normal() == job.output.preview.lexically_normal()) {
    const JsonValue& at = preview ? *preview : *image;
    at.fail(fmt::format("output.image and output.preview are the same file '{}'",
                        shown(job.output.image.string())));
  }
  if (job.frames) {
    check_frame_pattern(image, job.output.image, v);
    check_frame_pattern(preview, job.output.preview, v);
  }
  if (auto x = obj.get("video")) parse_video(*x, job);
}

// The name becomes part of the default output paths, so it must be one plain path component.
std::string parse_name(const JsonValue& v) {
  const std::string name = v.string();
  if (name.empty()) v.fail("expected a non-empty name");
  if (name == "." || name == "..") v.fail(fmt::format("'{}' is not a usable name", name));
  if (name.size() > kMaxNameBytes) {
    v.fail(fmt::format("a name of {} bytes; at most {} (it names the result files)", name.size(),
                       kMaxNameBytes));
  }
  for (char c : name) {
    if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20) {
      v.fail(fmt::format("'{}' must not contain '/', '\\' or control characters", shown(name)));
    }
  }
  return name;
}

WorkerRequirements parse_requirements(const JsonValue& v) {
  const JsonObject obj = v.object({"tags", "min_threads"});
  WorkerRequirements r;
  if (auto x = obj.get("tags")) {
    const std::vector<JsonValue> items = x->array();
    if (items.size() > kMaxWorkerTags) x->fail(fmt::format("{} tags; at most {}", items.size(), kMaxWorkerTags));
    for (const JsonValue& item : items) {
      std::string tag = item.string();
      if (const std::optional<std::string> problem = worker_tag_problem(tag)) item.fail(*problem);
      r.tags.push_back(std::move(tag));
    }
    sort_worker_tags(r.tags);
  }
  if (auto x = obj.get("min_threads")) r.min_threads = x->int32(0, kMaxRequiredThreads);
  return r;
}

JobCaps parse_limits(const JsonValue& v) {
  const JsonObject obj = v.object({"max_workers", "max_units_in_flight"});
  JobCaps caps;
  if (auto x = obj.get("max_workers")) caps.max_workers = x->int32(0, kMaxJobCap);
  if (auto x = obj.get("max_units_in_flight")) caps.max_units_in_flight = x->int32(0, kMaxJobCap);
  return caps;
}

std::string default_name(const fs::path& job_path) {
  std::string stem = job_path.stem().string();
  return stem.empty() ? "job" : stem;
}

}  // namespace

Job parse_job(const std::string& json_text, const fs::path& path, const JobLoadOptions& options) {
  return parse_job_document(parse_json_strict(json_text, path.string()), path, options);
}

Job parse_job_document(const nlohmann::json& doc, const fs::path& path, const JobLoadOptions& options) {
  const std::string file = path.string();
  const JsonObject top(JsonValue(doc, "", file),
                       {"version", "name", "frames", "animate", "scene", "render", "output", "validate",
                        "requirements", "limits"});

  // The version decides which keys exist, so it is checked before any of them.
  const JsonValue version = top.require("version");
  const std::int64_t v = version.integer();
  if (v != 1) version.fail(fmt::format("unsupported version {} (this farm reads version 1)", v));
  top.reject_unknown_keys();

  Context ctx;
  ctx.job_dir = path.empty() ? fs::current_path() : fs::absolute(path).parent_path();
  if (options.models_by_name) {
    ctx.asset_root = options.asset_root.lexically_normal();
    ctx.job_file = ctx.asset_root / (path.empty() ? fs::path("job.json") : path.filename());
    ctx.models_by_name = true;
  } else {
    const fs::path root = options.asset_root.empty() ? ctx.job_dir : fs::absolute(options.asset_root);
    std::error_code ec;
    ctx.asset_root = fs::weakly_canonical(root, ec);
    if (ec) throw InputError(fmt::format("{}: cannot resolve the asset root '{}': {}", file,
                                         root.string(), ec.message()));
    const fs::path job_dir = fs::weakly_canonical(ctx.job_dir, ec);
    if (ec) throw InputError(fmt::format("{}: cannot resolve its folder: {}", file, ec.message()));
    ctx.job_file = job_dir / (path.empty() ? fs::path("job.json") : path.filename());
    ctx.asset_root_hint = options.asset_root_hint;
  }

  Job job;
  job.path = path;
  job.asset_root = ctx.asset_root;
  job.name = default_name(path);
  if (auto x = top.get("name")) job.name = parse_name(*x);
  if (auto x = top.get("frames")) job.frames = parse_frames(*x);
  job.scene = parse_scene(top.require("scene"), ctx);
  if (auto x = top.get("render")) parse_render(*x, job.render);
  const std::string numbered = job.frames ? ".####" : "";
  job.output.image = fs::path("out") / (job.name + numbered + ".exr");
  job.output.preview = fs::path("out") / (job.name + numbered + ".png");
  if (auto x = top.get("output")) parse_output(*x, job);
  if (auto x = top.get("requirements")) job.requirements = parse_requirements(*x);
  if (auto x = top.get("limits")) job.caps = parse_limits(*x);
  if (auto x = top.get("validate")) {
    const JsonObject obj = x->object({"embree_rays"});
    if (auto rays = obj.get("embree_rays")) job.embree_rays = rays->integer(0, kMaxEmbreeRays);
  }
  if (auto x = top.get("animate")) {
    if (!job.frames) x->fail("keyframes need a frame range: give \"frames\": {\"start\": 1, \"end\": 48}");
    auto animation = std::make_shared<JobAnimation>(parse_animate(*x, doc));
    const std::size_t frames = job.frames->frames().size();
    if (!animation->tracks.empty()) {
      if (animation->tracks.size() * frames > kMaxAnimatedValueChecks) {
        x->fail(fmt::format("{} frames of {} keyframed values are too many to check: at most {} values over all "
                            "frames",
                            frames, animation->tracks.size(), kMaxAnimatedValueChecks));
      }
      // Every frame is checked here, so that no value an animation reaches (a negative intensity
      // where a smooth curve overshoots, a camera on its target) fails a job halfway. Each frame
      // writes every keyframed field, so one scene serves them all.
      JobScene scene = job.scene;
      for (int f : job.frames->frames()) animate_scene(*animation, scene, f, file);
      job.animation = std::move(animation);
    }
  }
  job.output_patterns = job.output;
  return job.frames ? job_at_frame(job, job.frames->frames().front()) : job;
}

std::vector<fs::path> job_named_files(const Job& job) {
  std::vector<fs::path> files;
  std::set<fs::path> named;  // a scene places one model file under many objects
  const auto add = [&](const fs::path& file) {
    if (named.insert(file).second) files.push_back(file);
  };
  for (const JobObject& o : job.scene.objects) add(o.file);
  if (job.scene.environment && !job.scene.environment->map.empty()) add(job.scene.environment->map);
  return files;
}

std::vector<int> job_frames(const Job& job) { return job.frames ? job.frames->frames() : std::vector<int>{0}; }

Job job_at_frame(const Job& job, int frame) {
  Job out = job;
  out.frame = frame;
  out.render.frame = frame;
  if (!job.frames) return out;
  out.seconds = job.frames->seconds_at(frame);
  if (job.animation) animate_scene(*job.animation, out.scene, frame, job.path.string());
  out.output.image = frame_file_name(job.output_patterns.image.string(), frame);
  out.output.preview = frame_file_name(job.output_patterns.preview.string(), frame);
  return out;
}

std::string read_job_file(const fs::path& path) {
  const std::string file = path.string();
  auto fail = [&](const std::string& what) -> void {
    throw InputError(fmt::format("{}: {}", file, what));
  };
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory) {
    fail(fmt::format("cannot read the job file: {}", ec.message()));
  }
  if (!fs::exists(status)) fail("no such job file");
  // Devices and FIFOs could block or never end; a job is always a plain file.
  if (!fs::is_regular_file(status)) fail("the job file is not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) fail(fmt::format("cannot read the job file: {}", ec.message()));
  if (size > kMaxJobFileBytes) {
    fail(fmt::format("the job file is {} bytes; the limit is {}", size, kMaxJobFileBytes));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(fmt::format("cannot open the job file: {}", std::generic_category().message(errno)));
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) fail("cannot read the job file");
  return text;
}

Job load_job(const fs::path& path, const JobLoadOptions& options) {
  return parse_job(read_job_file(path), path, options);
}

}  // namespace farm
