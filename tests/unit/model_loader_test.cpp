// Model loaders: Assimp (.dae .obj .ply) and tinygltf (.gltf .glb) behind load_model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>
#include <utility>

#include "renderer/scene/model.h"
#include "renderer/trace/bsdf.h"
#include "renderer/util/input_error.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const fs::path kShared = FARM_SHARED_ASSETS;
const fs::path kData = FARM_TEST_DATA;

// The lab's models live outside the repository; without them those tests have nothing to check.
#define REQUIRE_SHARED_ASSETS()                                                         \
  if (!fs::is_directory(kShared)) {                                                      \
    GTEST_SKIP() << "shared assets not found at " << kShared << " (../shared is absent)"; \
  }

using test::TempDir;

std::string read_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Loads `file` expecting an InputError; returns its message ("" and a test failure otherwise).
std::string input_error_of(const fs::path& file) {
  try {
    load_model(file);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << file << " loaded although an InputError was expected";
  return "";
}

const Mesh* find_mesh(const Model& model, const std::string& name) {
  for (const Mesh& m : model.meshes)
    if (m.name == name) return &m;
  return nullptr;
}

bool has_vertex(const Mesh& mesh, const glm::vec3& p, float tolerance = 1e-5f) {
  for (const glm::vec3& q : mesh.positions)
    if (glm::length(q - p) < tolerance) return true;
  return false;
}

void expect_near(const glm::vec3& actual, const glm::vec3& expected, float tolerance = 1e-5f) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

void expect_unit_normals(const Model& model) {
  for (const Mesh& m : model.meshes) {
    ASSERT_EQ(m.normals.size(), m.positions.size()) << m.name;
    for (const glm::vec3& n : m.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-4f) << m.name;
  }
}

void expect_valid_materials(const Model& model) {
  ASSERT_FALSE(model.materials.empty());
  for (const Mesh& m : model.meshes) EXPECT_LT(m.material, model.materials.size()) << m.name;
}

// ---- COLLADA and OBJ through Assimp (the lab's models) -----------------------------------------

// Triangle counts below were counted from the files' text, not from Assimp: a short script summed
// (vcount - 2) over every <polylist> of every instanced <geometry> in the .dae files, and
// (corners - 2) over every `f` line of the .obj.

TEST(LoaderCollada, CowHas5856Triangles) {
  REQUIRE_SHARED_ASSETS();
  const Model cow = load_model(kShared / "dae/cow.dae");
  // One <polylist count="5856"> whose vcount entries are all 3.
  EXPECT_EQ(cow.triangle_count(), 5856u);
  expect_unit_normals(cow);
  expect_valid_materials(cow);
}

TEST(LoaderCollada, CBbunnyHas28588Triangles) {
  REQUIRE_SHARED_ASSETS();
  const Model bunny = load_model(kShared / "dae/CBbunny.dae");
  // The bunny's polylist has 28576 triangles; six box walls (ceiling, light, floor, three walls)
  // are 2 triangles each: 28576 + 12.
  EXPECT_EQ(bunny.triangle_count(), 28588u);
  expect_unit_normals(bunny);
  expect_valid_materials(bunny);
}

TEST(LoaderObj, CornellBoxHas36Triangles) {
  REQUIRE_SHARED_ASSETS();
  const Model box = load_model(kShared / "obj/cornell_box.obj");
  // 18 quads (the front wall's face is commented out): floor 3, light, ceiling, back, green and
  // red wall 1 each, and 5 per block; 2 triangles per quad.
  EXPECT_EQ(box.triangle_count(), 36u);
  expect_valid_materials(box);
  const auto red = std::find_if(box.materials.begin(), box.materials.end(),
                                [](const Material& m) { return m.name == "red"; });
  ASSERT_NE(red, box.materials.end());
  expect_near(red->diffuse, {1.0f, 0.0f, 0.0f});
}

TEST(LoaderCollada, CowMaterialComesFromTheFile) {
  REQUIRE_SHARED_ASSETS();
  const Model cow = load_model(kShared / "dae/cow.dae");
  ASSERT_EQ(cow.materials.size(), 1u);
  const Material& m = cow.materials[0];
  expect_near(m.diffuse, glm::vec3(0.48f));
  expect_near(m.specular, glm::vec3(0.00625f));
  expect_near(m.ambient, glm::vec3(0.0f));
  EXPECT_FLOAT_EQ(m.shininess, 256.0f);
  EXPECT_FLOAT_EQ(m.ior, 1.0f);
  EXPECT_FLOAT_EQ(m.transmission, 0.0f);  // the file gives no transparency
}

TEST(LoaderCollada, CowCameraIsPlacedByItsNodeInYUpSpace) {
  REQUIRE_SHARED_ASSETS();
  const Model cow = load_model(kShared / "dae/cow.dae");
  ASSERT_EQ(cow.cameras.size(), 1u);
  const Camera& cam = cow.cameras[0];
  // The node puts the camera at (0,5,0) of the Z_UP file, looking along -Y at the cow; +Y up maps
  // (x,y,z) to (x,z,-y).
  expect_near(cam.position, {0.0f, 0.0f, -5.0f}, 1e-4f);
  expect_near(cam.forward(), {0.0f, 0.0f, 1.0f}, 1e-4f);
  expect_near(cam.up, {0.0f, 1.0f, 0.0f}, 1e-4f);
  // xfov 39.5978 degrees is the full horizontal angle; at aspect 16:9 that is a vertical
  // 2 atan(tan(19.7989 deg) / 1.777778) = 22.8952 degrees.
  ASSERT_TRUE(cam.aspect.has_value());
  EXPECT_NEAR(*cam.aspect, 1.777778f, 1e-5f);
  EXPECT_NEAR(cam.fov_y_degrees, 22.8952f, 1e-3f);
  EXPECT_NEAR(cam.near, 0.00999999f, 1e-7f);
  EXPECT_NEAR(cam.far, 10000.0f, 1e-2f);
}

TEST(LoaderCollada, CowDirectionalLightFollowsItsNode) {
  REQUIRE_SHARED_ASSETS();
  const Model cow = load_model(kShared / "dae/cow.dae");
  ASSERT_EQ(cow.lights.size(), 1u);
  const Light& light = cow.lights[0];
  EXPECT_EQ(light.kind, Light::Kind::Directional);
  expect_near(light.intensity, glm::vec3(1.0f));
  // The node's local -Z is -(0.5, 0.5, 0.7071) in the file; in +Y up that is (-0.5, -0.7071, 0.5):
  // shining downwards.
  expect_near(light.direction, {-0.5f, -0.7071068f, 0.5f}, 1e-4f);
}

TEST(LoaderCollada, CowBoundsAreFiniteAndYIsTheFilesUpAxis) {
  REQUIRE_SHARED_ASSETS();
  const AABB box = load_model(kShared / "dae/cow.dae").bounds();
  ASSERT_FALSE(box.empty());
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(std::isfinite(box.min[i]) && std::isfinite(box.max[i]));
  }
  // Position extremes read from the file: z (up) in [-0.7680434, 0.6891503], y in
  // [-0.833368, 0.6475131]. Converted to +Y up, the file's z becomes y and its y becomes -z.
  EXPECT_NEAR(box.min.y, -0.7680434f, 1e-5f);
  EXPECT_NEAR(box.max.y, 0.6891503f, 1e-5f);
  EXPECT_NEAR(box.min.z, -0.6475131f, 1e-5f);
  EXPECT_NEAR(box.max.z, 0.833368f, 1e-5f);
  EXPECT_NEAR(box.max.x, 0.4064897f, 1e-5f);
}

TEST(LoaderCollada, CBbunnyPointLightAndCameraAreReturned) {
  REQUIRE_SHARED_ASSETS();
  const Model bunny = load_model(kShared / "dae/CBbunny.dae");
  ASSERT_EQ(bunny.lights.size(), 1u);
  EXPECT_EQ(bunny.lights[0].kind, Light::Kind::Point);
  expect_near(bunny.lights[0].intensity, glm::vec3(10.0f));
  ASSERT_EQ(bunny.cameras.size(), 1u);
  EXPECT_GT(bunny.cameras[0].fov_y_degrees, 1.0f);
  EXPECT_LT(bunny.cameras[0].fov_y_degrees, 179.0f);
}

// Found by the fuzzer: Assimp reserves a <polylist>'s corners (the sum of its <vcount>) times its
// inputs before it reads <p>, so a vcount of 20 digits in a 1 kB file asked for 4.4 GB (22.9 GB
// in the fuzzer's input). The sum is held against the indices <p> holds; the honest polylist
// still loads.
TEST(LoaderCollada, APolylistWhoseVcountsNeedMoreIndicesThanItsPHoldsIsRefused) {
  TempDir dir;
  // The fuzzer's one-triangle seed (tests/fuzz/make_seeds.py), its <triangles> as a <polylist>.
  std::ifstream seed_file(std::string(FARM_SOURCE_DIR) + "/tests/fuzz/corpus/collada_loader/seed-triangle.dae");
  const std::string seed{std::istreambuf_iterator<char>(seed_file), std::istreambuf_iterator<char>()};
  const std::string triangles =
      R"(<triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>)";
  ASSERT_NE(seed.find(triangles), std::string::npos);
  const auto polylist = [&](const std::string& vcount) {
    std::string text = seed;
    return text.replace(text.find(triangles), triangles.size(),
                        R"(<polylist count="1"><input semantic="VERTEX" source="#v" offset="0"/><vcount>)" + vcount +
                            "</vcount><p>0 1 2</p></polylist>");
  };
  EXPECT_EQ(load_model(dir.write("honest.dae", polylist("3"))).triangle_count(), 1u);
  const auto error_of = [&](const std::string& name, const std::string& vcount) {
    try {
      load_model(dir.write(name, polylist(vcount)));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("loaded");
  };
  EXPECT_NE(error_of("huge.dae", "33333333333333333333").find(
                "huge.dae:10: <vcount>: polygons of more than 2^64 corners in all but 3 indices in <p>"),
            std::string::npos) << error_of("huge.dae", "33333333333333333333");
  EXPECT_NE(error_of("four.dae", "4").find("polygons of 4 corners in all but 3 indices in <p>"), std::string::npos)
      << error_of("four.dae", "4");
}

// Each of these is broken in its own way (a one-corner face, indices out of range, a zero index,
// a face that fails to triangulate, a missing .mtl). Either Assimp rejects it, and the message
// names the file, or Assimp loads it and the model is whole.
TEST(LoaderObj, BadFilesGiveInputErrorNamingTheFileOrLoad) {
  REQUIRE_SHARED_ASSETS();
  int seen = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(kShared / "bad")) {
    if (entry.path().extension() != ".obj") continue;
    ++seen;
    SCOPED_TRACE(entry.path().string());
    try {
      const Model m = load_model(entry.path());
      EXPECT_GT(m.triangle_count(), 0u);
      expect_valid_materials(m);
      expect_unit_normals(m);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(entry.path().filename().string()), std::string::npos)
          << e.what();
    }
  }
  EXPECT_GT(seen, 0);
}

// ---- glTF through tinygltf (tests/data/quad_scene.*, see make_gltf_assets.py) ------------------

void for_each_quad_scene(const std::function<void(const Model&)>& check) {
  for (const char* name : {"quad_scene.gltf", "quad_scene.glb"}) {
    SCOPED_TRACE(name);
    check(load_model(kData / name));
  }
}

TEST(LoaderGltf, QuadSceneHasFourTriangles) {
  for_each_quad_scene([](const Model& m) {
    EXPECT_EQ(m.triangle_count(), 4u);  // an indexed quad and a 4-vertex strip
    EXPECT_EQ(m.meshes.size(), 2u);
    expect_valid_materials(m);
    expect_unit_normals(m);
  });
}

TEST(LoaderGltf, NodeTransformsAreBakedIntoPositionsAndNormals) {
  for_each_quad_scene([](const Model& m) {
    const Mesh* quad = find_mesh(m, "quad");
    ASSERT_NE(quad, nullptr);
    // Corner (1,0,0): scale 2 -> (2,0,0); 90 deg about +Y -> (0,0,-2); + (1,2,3) -> (1,2,1);
    // parent's + (0,1,0) -> (1,3,1). Corner (1,1,0) likewise -> (1,5,1).
    EXPECT_TRUE(has_vertex(*quad, {1.0f, 3.0f, 1.0f}));
    EXPECT_TRUE(has_vertex(*quad, {1.0f, 5.0f, 1.0f}));
    for (const glm::vec3& n : quad->normals) expect_near(n, {1.0f, 0.0f, 0.0f});  // +Z turned to +X

    const Mesh* strip = find_mesh(m, "strip");  // node matrix translates by (0,0,-5)
    ASSERT_NE(strip, nullptr);
    EXPECT_TRUE(has_vertex(*strip, {1.0f, 1.0f, -5.0f}));
    EXPECT_EQ(strip->triangle_count(), 2u);
  });
}

TEST(LoaderGltf, PerspectiveCameraLooksDownItsNodesMinusZ) {
  for_each_quad_scene([](const Model& m) {
    ASSERT_EQ(m.cameras.size(), 1u);
    const Camera& cam = m.cameras[0];
    EXPECT_NEAR(cam.fov_y_degrees, glm::degrees(0.8f), 1e-4f);
    EXPECT_FLOAT_EQ(cam.near, 0.05f);
    EXPECT_FLOAT_EQ(cam.far, 200.0f);
    ASSERT_TRUE(cam.aspect.has_value());
    EXPECT_FLOAT_EQ(*cam.aspect, 1.5f);
    expect_near(cam.position, {0.0f, 1.0f, 10.0f});
    expect_near(cam.forward(), {0.0f, 0.0f, -1.0f});
    expect_near(cam.up, {0.0f, 1.0f, 0.0f});
  });
}

TEST(LoaderGltf, PunctualLightsBecomePointAndDirectionalLights) {
  for_each_quad_scene([](const Model& m) {
    ASSERT_EQ(m.lights.size(), 2u);
    const Light& lamp = m.lights[0];
    EXPECT_EQ(lamp.kind, Light::Kind::Point);
    expect_near(lamp.position, {0.0f, 4.0f, 0.0f});
    expect_near(lamp.intensity, {20.0f, 10.0f, 5.0f});  // colour times intensity
    const Light& sun = m.lights[1];
    EXPECT_EQ(sun.kind, Light::Kind::Directional);
    expect_near(sun.direction, {0.0f, -1.0f, 0.0f});
    expect_near(sun.intensity, glm::vec3(3.0f));
  });
}

TEST(LoaderGltf, MaterialsMapPbrAndExtensionsToPhong) {
  for_each_quad_scene([](const Model& m) {
    ASSERT_EQ(m.materials.size(), 3u);  // two from the file, our default for the strip
    const Material& emitter = m.materials[0];
    EXPECT_EQ(emitter.name, "emitter");
    expect_near(emitter.emission, {4.0f, 2.0f, 1.0f});  // emissiveFactor x emissiveStrength 4
    expect_near(emitter.diffuse, {0.8f, 0.2f, 0.1f});   // not metallic: all of the base colour
    expect_near(emitter.specular, glm::vec3(0.04f));
    EXPECT_NEAR(emitter.shininess, 30.0f, 1e-3f);  // 2 / 0.5^4 - 2
    // ... which the path tracer turns back into glTF's GGX alpha = roughness^2.
    EXPECT_NEAR(Bsdf::roughness_from_shininess(emitter.shininess), 0.25f, 1e-5f);
    EXPECT_EQ(emitter.emission_sides, EmissionSides::Front);  // glTF's doubleSided defaults to false
    const Material& glass = m.materials[1];
    EXPECT_EQ(glass.emission_sides, EmissionSides::Both);  // doubleSided: seen, and shining, both ways
    EXPECT_FLOAT_EQ(glass.ior, 1.5f);
    EXPECT_FLOAT_EQ(glass.transmission, 0.9f);
    EXPECT_TRUE(glass.is_mirror());  // roughness 0
    const Mesh* strip = find_mesh(m, "strip");
    ASSERT_NE(strip, nullptr);
    EXPECT_EQ(strip->material, 2u);
    expect_near(m.materials[2].diffuse, Material{}.diffuse);
  });
}

TEST(LoaderGltf, TruncatedFilesGiveInputErrorNamingTheFile) {
  TempDir dir;
  const std::string text = read_file(kData / "quad_scene.gltf");
  const std::string glb = read_file(kData / "quad_scene.glb");
  ASSERT_FALSE(text.empty());
  ASSERT_FALSE(glb.empty());
  const fs::path cut_text = dir.write("cut_text.gltf", text.substr(0, text.size() / 2));
  const fs::path cut_glb = dir.write("cut_binary.glb", glb.substr(0, glb.size() - 40));
  const fs::path empty = dir.write("empty.gltf", "");
  const fs::path garbage = dir.write("garbage.glb", "this is not a binary glTF file at all");
  for (const fs::path& file : {cut_text, cut_glb, empty, garbage}) {
    SCOPED_TRACE(file.string());
    EXPECT_NE(input_error_of(file).find(file.filename().string()), std::string::npos);
  }
}

// Well-formed JSON describing impossible data: each must end in an InputError naming the file, and
// never in a read outside the buffers (the suite runs clean under -fsanitize=address).
TEST(LoaderGltf, MalformedAccessorsAndReferencesGiveInputError) {
  using nlohmann::json;
  TempDir dir;
  dir.write("outside.bin", std::string(200, 'x'));  // beside the model's folder, not inside it
  const json good = json::parse(read_file(kData / "quad_scene.gltf"));
  auto attributes = [](json& j, int mesh) -> json& {
    return j["meshes"][mesh]["primitives"][0]["attributes"];
  };
  const std::pair<const char*, std::function<void(json&)>> cases[] = {
      {"count_past_buffer", [](json& j) { j["accessors"][3]["count"] = 100000; }},
      {"offset_past_view", [](json& j) { j["accessors"][1]["byteOffset"] = 90; }},
      {"view_past_buffer", [](json& j) { j["bufferViews"][2]["byteLength"] = 4800; }},
      {"stride_below_element", [](json& j) { j["bufferViews"][0]["byteStride"] = 8; }},
      {"index_past_vertices", [](json& j) {
         j["accessors"][0]["count"] = 2;
         j["accessors"][1]["count"] = 2;
       }},
      {"normal_count_differs", [](json& j) { j["accessors"][1]["count"] = 3; }},
      {"partial_triangle", [](json& j) { j["accessors"][2]["count"] = 5; }},
      {"index_type_signed", [](json& j) { j["accessors"][2]["componentType"] = 5122; }},
      {"position_not_vec3", [](json& j) { j["accessors"][3]["type"] = "VEC2"; }},
      {"missing_accessor", [&](json& j) { attributes(j, 1)["POSITION"] = 42; }},
      {"missing_mesh", [](json& j) { j["nodes"][1]["mesh"] = 7; }},
      {"missing_material", [](json& j) { j["meshes"][0]["primitives"][0]["material"] = 9; }},
      {"missing_camera", [](json& j) { j["nodes"][3]["camera"] = 4; }},
      {"missing_light",
       [](json& j) { j["nodes"][4]["extensions"]["KHR_lights_punctual"]["light"] = 5; }},
      {"missing_child", [](json& j) { j["nodes"][0]["children"] = {99}; }},
      {"node_cycle", [](json& j) { j["nodes"][1]["children"] = {0}; }},
      {"bad_primitive_mode", [](json& j) { j["meshes"][0]["primitives"][0]["mode"] = 9; }},
      {"buffer_outside_folder", [](json& j) { j["buffers"][0]["uri"] = "../outside.bin"; }},
      {"no_triangles", [](json& j) {
         j["meshes"][0]["primitives"][0]["mode"] = 0;  // points
         j["meshes"][1]["primitives"][0]["mode"] = 1;  // lines
       }},
  };
  for (const auto& [name, mutate] : cases) {
    SCOPED_TRACE(name);
    json broken = good;
    mutate(broken);
    const fs::path file = dir.write("model/" + std::string(name) + ".gltf", broken.dump());
    EXPECT_NE(input_error_of(file).find(file.filename().string()), std::string::npos);
  }
}

// Every prefix of the .glb and every single-byte corruption of it: each either loads (a corrupted
// float is still a float) or gives an InputError naming the file; none may crash or read out of
// bounds.
TEST(LoaderGltf, EveryTruncationAndByteCorruptionOfTheGlbFailsCleanly) {
  TempDir dir;
  const std::string glb = read_file(kData / "quad_scene.glb");
  ASSERT_FALSE(glb.empty());
  auto try_load = [&](const std::string& bytes, const std::string& what) {
    const fs::path file = dir.write("mutant.glb", bytes);
    try {
      const Model m = load_model(file);
      EXPECT_GT(m.triangle_count(), 0u) << what;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("mutant.glb"), std::string::npos)
          << what << ": " << e.what();
    }
  };
  for (std::size_t n = 0; n < glb.size(); ++n) {
    try_load(glb.substr(0, n), "first " + std::to_string(n) + " bytes");
  }
  for (std::size_t i = 0; i < glb.size(); ++i) {
    std::string bytes = glb;
    bytes[i] = static_cast<char>(~static_cast<unsigned char>(bytes[i]));
    try_load(bytes, "byte " + std::to_string(i) + " inverted");
  }
}

// ---- Normals ------------------------------------------------------------------------------------

TEST(LoaderNormals, ModelWithoutNormalsGetsSmoothUnitNormals) {
  TempDir dir;
  // A shallow roof: two slopes 53 degrees apart (within the 60 degree crease angle) meeting at a
  // ridge along x, no `vn` lines. Normals are area weighted and each ridge vertex has equal area
  // on both slopes, so its normal points straight up.
  const fs::path roof = dir.write("roof.obj",
                                  "v 0 0 1\nv 1 0 1\nv 1 0.5 0\nv 0 0.5 0\nv 1 0 -1\nv 0 0 -1\n"
                                  "f 1 2 3\nf 1 3 4\nf 3 5 6\nf 3 6 4\n");
  const Model m = load_model(roof);
  ASSERT_EQ(m.triangle_count(), 4u);
  expect_unit_normals(m);
  const Mesh& mesh = m.meshes.at(0);
  const glm::vec3 up_slope = glm::normalize(glm::vec3(0.0f, 1.0f, 0.5f));
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const glm::vec3& p = mesh.positions[i];
    SCOPED_TRACE(testing::Message() << "vertex " << p.x << " " << p.y << " " << p.z);
    if (p.y == 0.5f) expect_near(mesh.normals[i], {0.0f, 1.0f, 0.0f});  // ridge: both slopes
    else expect_near(mesh.normals[i], {0.0f, up_slope.y, p.z > 0.0f ? up_slope.z : -up_slope.z});
  }
}

TEST(LoaderNormals, SteepRidgeBeyondTheCreaseAngleStaysSharp) {
  TempDir dir;
  // Slopes 90 degrees apart: each face keeps its own normal at the shared ridge.
  const fs::path roof = dir.write("steep.obj",
                                  "v 0 0 1\nv 1 0 1\nv 1 1 0\nv 0 1 0\nv 1 0 -1\nv 0 0 -1\n"
                                  "f 1 2 3\nf 1 3 4\nf 3 5 6\nf 3 6 4\n");
  const Model m = load_model(roof);
  expect_unit_normals(m);
  const Mesh& mesh = m.meshes.at(0);
  const float s = std::sqrt(0.5f);
  for (const glm::uvec3& t : mesh.triangles) {
    const glm::vec3 face = glm::normalize(glm::cross(mesh.positions[t.y] - mesh.positions[t.x],
                                                     mesh.positions[t.z] - mesh.positions[t.x]));
    ASSERT_NEAR(std::fabs(face.z), s, 1e-5f);
    for (int k = 0; k < 3; ++k) expect_near(mesh.normals[t[k]], face);
  }
}

TEST(LoaderNormals, GltfPrimitiveWithoutNormalsGetsThem) {
  const Model m = load_model(kData / "quad_scene.gltf");
  const Mesh* strip = find_mesh(m, "strip");
  ASSERT_NE(strip, nullptr);
  ASSERT_EQ(strip->normals.size(), strip->positions.size());
  for (const glm::vec3& n : strip->normals) expect_near(n, {0.0f, 0.0f, 1.0f});
}

// ---- load_model's own checks --------------------------------------------------------------------

TEST(ModelLoader, UnknownExtensionNamesTheFileAndTheSupportedFormats) {
  TempDir dir;
  const fs::path file = dir.write("scene.fbx", "whatever");
  const std::string message = input_error_of(file);
  EXPECT_NE(message.find("scene.fbx"), std::string::npos) << message;
  for (const char* ext : {".dae", ".obj", ".ply", ".gltf", ".glb"}) {
    EXPECT_NE(message.find(ext), std::string::npos) << message;
  }
}

TEST(ModelLoader, MissingFileNamesTheFile) {
  TempDir dir;
  for (const char* name : {"absent.obj", "absent.dae", "absent.gltf", "absent.glb"}) {
    const std::string message = input_error_of(dir.path() / name);
    EXPECT_NE(message.find(name), std::string::npos) << message;
  }
}

TEST(ModelLoader, DirectoryIsNotAModel) {
  TempDir dir;
  fs::create_directory(dir.path() / "folder.obj");
  EXPECT_NE(input_error_of(dir.path() / "folder.obj").find("folder.obj"), std::string::npos);
}

TEST(ModelLoader, ExtensionMatchesWhateverItsCase) {
  TempDir dir;
  const fs::path upper = dir.write("QUAD.GLB", read_file(kData / "quad_scene.glb"));
  EXPECT_EQ(load_model(upper).triangle_count(), 4u);
}

TEST(ModelLoader, FileWithOnlyLinesGivesInputErrorNamingIt) {
  TempDir dir;
  const fs::path file = dir.write("wire.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n");
  EXPECT_NE(input_error_of(file).find("wire.obj"), std::string::npos);
}

}  // namespace
}  // namespace farm
