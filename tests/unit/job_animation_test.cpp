// Keyframes bound to the parsed job (renderer/job/job_animation.h, animation_binding.h): frame k
// of an animated job is, float for float, the job with the values at k written into its file by
// hand; a value refused at a frame gets the message it would get written in by hand; paths the
// format cannot animate are refused when the job is parsed; and a frame is made from the parsed
// scene, not by reading JSON again.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "renderer/job/job.h"
#include "renderer/job/keyframes.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// A job beside jobs/cornell.json, reading its Cornell box.
const fs::path kJobFile = fs::path(FARM_SOURCE_DIR) / "jobs" / "animated.json";
// What a refusal at a frame adds to the message of the job written by hand.
std::string at_frame(int frame) { return fmt::format(" (at frame {}, with the animated values)", frame); }

Job parse(const Json& doc) { return parse_job(doc.dump(), kJobFile); }

std::string error_of(const Json& doc) {
  try {
    parse(doc);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

Json track(const std::string& path, std::vector<std::pair<double, Json>> keys, const std::string& interpolation = "linear") {
  Json t{{"value", path}, {"interpolation", interpolation}, {"keys", Json::array()}};
  for (auto& [frame, value] : keys) t["keys"].push_back({{"frame", frame}, {"value", value}});
  return t;
}

Json object(Json extra = Json::object()) {
  Json o{{"file", "assets/cornell_box.obj"}};
  o.update(extra);
  return o;
}

// Frames 1 to 12 of a scene whose every kind of value is keyframed below.
Json base_job() {
  return Json{{"version", 1},
              {"frames", {{"start", 1}, {"end", 12}}},
              {"output", {{"image", "out/anim.####.exr"}}},
              {"scene",
               {{"objects",
                 {object({{"rotate", {{"axis", {0, 1, 0}}, {"degrees", 10}}},
                          {"scale", {1, 2, 3}},
                          {"material", {{"diffuse", {0.25, 0.5, 0.75}}}}}),
                  object()}},
                {"camera", {{"position", {0, 0, 4}}, {"target", {0, 0, 0}}, {"fov_y", 40}}},
                {"lights",
                 {{{"position", {0, 0.6, 0.5}}, {"intensity", 1.5}},
                  {{"position", {0.2, 0.6, 0.5}}},
                  {{"position", {-0.2, 0.6, 0.5}}, {"intensity", {1, 2, 3}}}}},
                {"ambient", {0.125, 0.125, 0.125}},
                {"background", {0, 0, 0}}}},
              {"render", {{"width", 16}, {"height", 16}}}};
}

Json with_tracks(Json doc, std::vector<Json> tracks) {
  doc["animate"] = tracks;
  return doc;
}

// "scene.objects[0].rotate.degrees" -> "/scene/objects/0/rotate/degrees"
Json::json_pointer pointer(const std::string& path) {
  std::string out = "/";
  for (char c : path) {
    if (c == '.' || c == '[') {
      out += '/';
    } else if (c != ']') {
      out += c;
    }
  }
  return Json::json_pointer(out);
}

// The job at `frame` as a person would write it: every track's value at the frame written into the
// file's text (keys rounded to float, as the job reads them), the keyframes dropped, the range
// that one frame. What the farm did before keyframes were bound to the parsed job.
Json by_hand(Json doc, int frame) {
  for (const Json& t : doc["animate"]) {
    KeyframeTrack track;
    const std::string interpolation = t.value("interpolation", "linear");
    track.interpolation = interpolation == "step"     ? Interpolation::Step
                          : interpolation == "smooth" ? Interpolation::Smooth
                                                      : Interpolation::Linear;
    bool scalar = true;
    for (const Json& k : t["keys"]) {
      Keyframe key;
      key.frame = static_cast<double>(k["frame"].get<float>());
      scalar = k["value"].is_number();
      for (const Json& x : scalar ? Json::array({k["value"]}) : k["value"]) {
        key.value.push_back(static_cast<double>(x.get<float>()));
      }
      track.keys.push_back(key);
    }
    const std::vector<double> v = track.at(frame);
    doc[pointer(t["value"].get<std::string>())] = scalar ? Json(v[0]) : Json(v);
  }
  doc.erase("animate");
  doc["frames"] = {{"start", frame}, {"end", frame}};
  return doc;
}

// Every value of a parsed scene, floats as their shortest exact text: equal texts, equal floats.
std::string text(const glm::vec3& v) { return fmt::format("({}, {}, {})", v.x, v.y, v.z); }
template <typename T>
std::string text(const std::optional<T>& v) {
  if (!v) return "none";
  if constexpr (std::is_same_v<T, glm::vec3>) {
    return text(*v);
  } else {
    return fmt::format("{}", *v);
  }
}
std::string text(const JobScene& s) {
  std::string out;
  for (const JobObject& o : s.objects) {
    const ObjectTransform& t = o.transform;
    const MaterialOverride& m = o.material;
    out += fmt::format("object {}: translate {} axis {} degrees {} scale {}; material {} {} {} {} {} {} {}\n",
                       o.file_as_written, text(t.translate), text(t.rotate_axis), t.rotate_degrees, text(t.scale),
                       text(m.ambient), text(m.diffuse), text(m.specular), text(m.emission), text(m.shininess),
                       text(m.ior), text(m.transmission));
  }
  if (s.camera) {
    const Camera& c = *s.camera;
    out += fmt::format("camera: {} {} {} fov {} near {} far {} aspect {}\n", text(c.position), text(c.target),
                       text(c.up), c.fov_y_degrees, c.near, c.far, text(c.aspect));
  }
  for (const Light& l : s.lights ? *s.lights : std::vector<Light>{}) {
    out += fmt::format("light: {} {}\n", text(l.position), text(l.intensity));
  }
  return out + fmt::format("ambient {} background {}\n", text(s.ambient), text(s.background));
}

// Tracks on every kind of binding: object transforms (whole, one component, keys the job does not
// write), material overrides (given or not), every camera value (a whole vector, then one of its
// components), a light's intensity as a number, as 3 numbers and one component, the scene's.
std::vector<Json> every_kind_of_track() {
  return {
      track("scene.objects[0].translate", {{1, {0, 0, 0}}, {6, {0.5, -1, 2}}, {12, {1, 1, 1}}}, "smooth"),
      track("scene.objects[0].rotate.axis[0]", {{1, 0}, {12, 1}}),
      track("scene.objects[0].rotate.degrees", {{1, 10}, {12, 100}}),
      track("scene.objects[0].scale[2]", {{1, 3}, {5, 0.5}, {9, 7}}, "step"),
      track("scene.objects[0].material.diffuse[1]", {{1, 0.5}, {12, 0.1}}),
      track("scene.objects[0].material.specular", {{1, {0, 0, 0}}, {12, {1, 0.5, 0.25}}}),
      track("scene.objects[0].material.emission", {{1, {0, 0, 0}}, {12, {3, 3, 3}}}, "smooth"),
      track("scene.objects[0].material.shininess", {{1, 5}, {12, 50}}),
      track("scene.objects[0].material.ior", {{1, 1.33}, {12, 1.5}}),
      track("scene.objects[0].material.transmission", {{1, 0}, {12, 0.9}}),
      track("scene.objects[0].material.ambient", {{3, {1, 1, 1}}, {7, {0.5, 0.5, 0.5}}}),
      track("scene.objects[1].rotate.degrees", {{1, 0}, {4, 30}, {12, 720}}, "smooth"),
      track("scene.objects[1].material.diffuse", {{1, {0.1, 0.2, 0.3}}, {12, {0.3, 0.2, 0.1}}}),
      track("scene.objects[1].scale", {{1, {1, 1, 1}}, {12, {-2, 0.5, 1}}}, "step"),
      track("scene.camera.position", {{1, {0, 0, 4}}, {12, {1, 0.5, 4}}}),
      track("scene.camera.position[1]", {{1, 0}, {12, 0.75}}),
      track("scene.camera.target", {{1, {0, 0, 0}}, {12, {0, 0.5, 0}}}),
      track("scene.camera.up", {{1, {0, 1, 0}}, {12, {0.5, 1, 0}}}),
      track("scene.camera.fov_y", {{1, 40}, {12, 50}}, "smooth"),
      track("scene.camera.near", {{1, 0.1}, {12, 0.5}}),
      track("scene.camera.far", {{1, 10}, {12, 20}}),
      track("scene.camera.aspect", {{1, 1}, {12, 1.5}}),
      track("scene.lights[0].intensity", {{1, 1.5}, {12, 0.3}}),
      track("scene.lights[0].position[0]", {{1, 0}, {12, 0.3}}),
      track("scene.lights[1].intensity", {{1, {1, 2, 3}}, {12, {3, 2, 1}}}, "smooth"),
      track("scene.lights[2].intensity[2]", {{1, 3}, {12, 0.7}}),
      track("scene.ambient[1]", {{1, 0.125}, {12, 0.4}}),
      track("scene.background[0]", {{1, 0.9}, {12, 0.8}}),
      track("scene.background", {{1, {0, 0, 0}}, {12, {0.5, 0.25, 0}}}),
  };
}

TEST(JobAnimation, EveryFrameIsTheJobWrittenByHandFloatForFloat) {
  const Json doc = with_tracks(base_job(), every_kind_of_track());
  const Job job = parse(doc);
  for (int frame = 1; frame <= 12; ++frame) {
    const Job at = job_at_frame(job, frame);
    EXPECT_EQ(text(at.scene), text(parse(by_hand(doc, frame)).scene)) << "frame " << frame;
  }
  // Spot checks of what the text compares: a whole vector then one of its components, the
  // rotate axis normalised with its keyframed component, a number making a grey intensity, and a
  // component track before a whole one (the whole one, listed later, wins).
  const Job at = job_at_frame(job, 12);
  EXPECT_EQ(text(at.scene.camera->position), "(1, 0.75, 4)");
  EXPECT_FLOAT_EQ(at.scene.objects[0].transform.rotate_axis.x, std::sqrt(0.5f));
  EXPECT_FLOAT_EQ(at.scene.objects[0].transform.rotate_axis.y, std::sqrt(0.5f));
  EXPECT_EQ(text((*at.scene.lights)[0].intensity), "(0.3, 0.3, 0.3)");
  EXPECT_EQ(text((*at.scene.lights)[2].intensity), "(1, 2, 0.7)");
  EXPECT_EQ(text(at.scene.background), "(0.5, 0.25, 0)");
  EXPECT_EQ(text(at.scene.objects[1].material.diffuse), "(0.3, 0.2, 0.1)");
  EXPECT_FALSE(at.scene.objects[1].material.specular);
  // A linear track in between keys: frame 5 of 10 to 100 over frames 1 to 12.
  EXPECT_EQ(job_at_frame(job, 5).scene.objects[0].transform.rotate_degrees, static_cast<float>(10.0 + 90.0 * (4.0 / 11.0)));
}

TEST(JobAnimation, AJobWithoutACameraAnimatesTheDefaultCamera) {
  Json doc = base_job();
  doc["scene"].erase("camera");
  doc = with_tracks(doc, {track("scene.camera.fov_y", {{1, 30}, {12, 60}})});
  const Job job = parse(doc);
  const Job at = job_at_frame(job, 12);
  ASSERT_TRUE(at.scene.camera);
  EXPECT_EQ(at.scene.camera->fov_y_degrees, 60.0f);
  const Camera defaults;
  EXPECT_EQ(at.scene.camera->position, defaults.position);
  EXPECT_EQ(at.scene.camera->far, defaults.far);
  for (int frame : {1, 7}) EXPECT_EQ(text(job_at_frame(job, frame).scene), text(parse(by_hand(doc, frame)).scene));
  // A camera key the default camera gets only from a track is named in a refusal as given.
  doc["animate"] = {track("scene.camera.far", {{1, 10}, {12, 0.05}})};
  EXPECT_EQ(error_of(doc), kJobFile.string() + ": scene.camera.far: expected far > near (0.1), got 0.05" +
                               at_frame(12));
}

TEST(JobAnimation, AnIntensityIsANumberOrThreeNumbers) {
  Json doc = with_tracks(base_job(), {track("scene.lights[1].intensity", {{1, 2}, {12, 4}})});
  EXPECT_EQ(text((*job_at_frame(parse(doc), 12).scene.lights)[1].intensity), "(4, 4, 4)");
  doc["animate"] = {track("scene.lights[1].intensity", {{1, {1, 2, 3}}, {12, {4, 5, 6}}})};
  EXPECT_EQ(text((*job_at_frame(parse(doc), 12).scene.lights)[1].intensity), "(4, 5, 6)");
  doc["animate"] = {track("scene.lights[1].intensity", {{1, {1, 2}}, {12, {4, 5}}})};
  EXPECT_EQ(error_of(doc), kJobFile.string() + ": animate[0].keys[0].value: expected a number or 3 numbers for "
                                               "scene.lights[1].intensity, got 2 numbers");
  // Written as a number, it is keyframed as one.
  doc["animate"] = {track("scene.lights[0].intensity", {{1, {1, 2, 3}}, {12, {4, 5, 6}}})};
  EXPECT_EQ(error_of(doc), kJobFile.string() + ": animate[0].keys[0].value: expected a number like "
                                               "scene.lights[0].intensity, got 3 numbers");
}

TEST(JobAnimation, PathsTheFormatCannotAnimateAreRefusedWhenTheJobIsParsed) {
  const auto refused = [](Json doc, const std::string& path, Json key) {
    doc["animate"] = {track(path, {{1, key}, {12, key}})};
    return error_of(doc);
  };
  const std::string at = kJobFile.string() + ": animate[0].value: ";
  Json doc = base_job();
  const std::string not_an_object_value =
      "cannot be animated (keyframes animate translate, rotate, scale or material of scene.objects[0])";
  EXPECT_EQ(refused(doc, "scene.objects[0].animation", 1), at + "'scene.objects[0].animation' " + not_an_object_value);
  doc["scene"]["objects"][0]["animation"] = 0;  // a number the job writes, but no value of the scene
  EXPECT_EQ(refused(doc, "scene.objects[0].animation", 1), at + "'scene.objects[0].animation' " + not_an_object_value);
  EXPECT_EQ(refused(doc, "scene.objects[0].material.emission_sides", 1),
            at + "'scene.objects[0].material.emission_sides' cannot be animated (keyframes animate ambient, diffuse, "
                 "specular, emission, shininess, ior or transmission of scene.objects[0].material)");
  EXPECT_EQ(refused(doc, "scene.camera.zoom", 1),
            at + "'scene.camera.zoom': scene.camera has no key 'zoom' (expected position, target, up, fov_y, near, "
                 "far or aspect)");
  EXPECT_EQ(refused(doc, "scene.objects[1].rotate", 1), at + "'scene.objects[1].rotate' is an object, not a number or a vector");
  EXPECT_EQ(refused(doc, "scene.objects[1].material.shininess.x", 1), at + "'scene.objects[1].material.shininess.x' names nothing in the job");
  doc["scene"].erase("camera");
  EXPECT_EQ(refused(doc, "scene.camera.zoom", 1),
            at + "'scene.camera.zoom': scene.camera has no key 'zoom' (expected position, target, up, fov_y, near, "
                 "far or aspect)");
  EXPECT_EQ(refused(doc, "scene.camera", 1), at + "'scene.camera' is an object, not a number or a vector");
  // A value the job does not write has the format's shape.
  EXPECT_EQ(refused(doc, "scene.camera.position", 1),
            kJobFile.string() + ": animate[0].keys[0].value: expected 3 numbers for scene.camera.position, got a number");
  EXPECT_EQ(refused(doc, "scene.camera.near", Json{1, 2, 3}),
            kJobFile.string() + ": animate[0].keys[0].value: expected a number for scene.camera.near, got 3 numbers");
}

TEST(JobAnimation, AValueRefusedAtAFrameHasTheMessageOfTheJobWrittenByHand) {
  Json far_given = base_job();
  far_given["scene"]["camera"]["far"] = 10;
  Json camera_above = base_job();
  camera_above["scene"]["camera"]["position"] = {0, 4, 0.5};
  struct Case {
    Json doc;
    Json track;
    std::string wanted;  // the message of the first frame refused, without the file and the frame
  };
  const std::vector<Case> cases = {
      {base_job(), track("scene.lights[0].intensity", {{1, 1}, {9, -1}}),
       "scene.lights[0].intensity: expected a number >= 0, got -0.25"},
      {base_job(), track("scene.lights[1].intensity", {{1, {1, 1, 1}}, {9, {1, -1, 1}}}),
       "scene.lights[1].intensity[1]: expected a number >= 0, got -0.25"},
      {base_job(), track("scene.lights[2].intensity[0]", {{1, 1}, {9, -1}}),
       "scene.lights[2].intensity[0]: expected a number >= 0, got -0.25"},
      {base_job(), track("scene.objects[0].scale[1]", {{1, 1}, {9, -1}}),
       "scene.objects[0].scale[1]: expected a non-zero scale factor, got 0"},
      {base_job(), track("scene.objects[0].rotate.axis[1]", {{1, 1}, {9, -1}}),
       "scene.objects[0].rotate.axis: expected a non-zero axis, got (0, 0, 0)"},
      {base_job(), track("scene.objects[1].rotate.axis", {{1, {0, 1, 0}}, {9, {0, -1, 0}}}),
       "scene.objects[1].rotate.axis: expected a non-zero axis, got (0, 0, 0)"},
      {base_job(), track("scene.objects[0].material.transmission", {{1, 0.5}, {9, 1.5}}),
       "scene.objects[0].material.transmission: expected a number <= 1, got 1.125"},
      {base_job(), track("scene.objects[0].material.ior", {{1, 1}, {9, -1}}),
       "scene.objects[0].material.ior: expected a number > 0, got 0.0"},
      {base_job(), track("scene.objects[0].material.shininess", {{1, 1}, {9, -1}}),
       "scene.objects[0].material.shininess: expected a number >= 0, got -0.25"},
      {base_job(), track("scene.objects[0].material.diffuse[2]", {{1, 1}, {9, -1}}),
       "scene.objects[0].material.diffuse[2]: expected a number >= 0, got -0.25"},
      {base_job(), track("scene.ambient", {{1, {1, 1, 1}}, {9, {-1, 1, 1}}}),
       "scene.ambient[0]: expected a number >= 0, got -0.25"},
      {base_job(), track("scene.camera.aspect", {{1, 1}, {9, -1}}), "scene.camera.aspect: expected a number > 0, got 0.0"},
      {base_job(), track("scene.camera.near", {{1, 1}, {9, 17}}),
       "scene.camera.near: expected near < far (10, the default), got 11"},
      {far_given, track("scene.camera.near", {{1, 1}, {9, 17}}), "scene.camera.far: expected far > near (11), got 10"},
      {base_job(), track("scene.camera.position", {{1, {0, 0, 4}}, {9, {0, 0, -4}}}),
       "scene.camera: position and target are the same point (0, 0, 0)"},
      {camera_above, track("scene.camera.position[2]", {{1, 0.5}, {9, -0.5}}),
       "scene.camera.up: the default up (0, 1, 0) is parallel to the viewing direction (target - position)"},
      {base_job(), track("scene.camera.up", {{1, {0, 1, 0}}, {9, {0, 0, -4}}}),
       "scene.camera.up: up (0, 0, -4) is parallel to the viewing direction (target - position)"},
  };
  for (const Case& c : cases) {
    Json doc = c.doc;
    doc["animate"] = {c.track};
    const std::string refused = error_of(doc);
    int frame = 1;
    std::string by_hand_error = "(no error)";
    for (; frame <= 12 && by_hand_error == "(no error)"; ++frame) by_hand_error = error_of(by_hand(doc, frame));
    --frame;
    EXPECT_EQ(refused, kJobFile.string() + ": " + c.wanted + at_frame(frame)) << c.track.dump();
    EXPECT_EQ(refused, by_hand_error + at_frame(frame)) << c.track.dump();
  }
}

TEST(JobAnimation, AFrameIsMadeFromTheParsedSceneNotByReadingTheJobAgain) {
  Job job = parse(with_tracks(base_job(), {track("scene.objects[0].rotate.degrees", {{1, 0}, {12, 110}})}));
  // Values no track writes, changed in the parsed job (as no file says), stay as they are at
  // every frame; the keyframed one is written.
  job.scene.objects[0].transform.translate = glm::vec3(7.0f, 8.0f, 9.0f);
  job.scene.objects[1].file_as_written = "elsewhere.obj";
  job.scene.ambient = glm::vec3(0.5f);
  const Job at = job_at_frame(job, 12);
  EXPECT_EQ(text(at.scene.objects[0].transform.translate), "(7, 8, 9)");
  EXPECT_EQ(at.scene.objects[1].file_as_written, "elsewhere.obj");
  EXPECT_EQ(text(at.scene.ambient), "(0.5, 0.5, 0.5)");
  EXPECT_EQ(at.scene.objects[0].transform.rotate_degrees, 110.0f);
  EXPECT_EQ(job_at_frame(at, 2).scene.objects[0].transform.rotate_degrees, 10.0f);
}

}  // namespace
}  // namespace farm
