// Texture coordinates and the textures materials name, as the loaders read them: OBJ/MTL through
// Assimp and glTF through tinygltf, each texture confined to the asset root and decoded once per
// process however many models name it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <glm/geometric.hpp>
#include <iterator>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/png_writer.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "renderer/scene/model.h"
#include "renderer/texture/material_textures.h"
#include "renderer/texture/texture_cache.h"
#include "renderer/util/input_error.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// An 8-bit RGB PNG of `pixels` (rows top to bottom).
void write_rgb_png(const fs::path& file, int width, int height, std::vector<std::uint8_t> pixels) {
  Rgb8Image image;
  image.width = width;
  image.height = height;
  image.pixels = std::move(pixels);
  std::FILE* out = std::fopen(file.c_str(), "wb");
  ASSERT_NE(out, nullptr);
  write_png(image, out, file);
  std::fclose(out);
}

// A 2x2 RGB PNG: red, green / blue, white (rows top to bottom), 8-bit sRGB-encoded 255 and 0 only,
// so its linear values are exactly 1 and 0.
void write_checker_png(const fs::path& file) {
  write_rgb_png(file, 2, 2, {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255});
}

// The glTF triangle every test below textures: positions (0,0,0), (1,0,0), (0,1,0) with texcoords
// (0,1), (1,1), (1,0), little-endian floats in tri.bin (positions then texcoords), written beside
// `name`, whose `texturing` (its "images", "samplers", "textures" and "materials", comma-separated
// JSON members) the test gives. Returns the .gltf's path.
const float kTriangleData[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.0f, 1.0f, 1.0f, 1.0f, 0.0f, 0.0f};

fs::path write_textured_triangle(const TempDir& dir, const std::string& name, const std::string& texturing) {
  dir.write("tri.bin", std::string(reinterpret_cast<const char*>(kTriangleData), sizeof kTriangleData));
  return dir.write(name, R"({
    "asset": {"version": "2.0"},
    "buffers": [{"uri": "tri.bin", "byteLength": 60}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
      {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
    "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0,
    )" + texturing + "}");
}

// One textured triangle: its vt's v points up, as OBJ's does.
constexpr const char* kTexturedObj =
    "mtllib m.mtl\n"
    "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
    "vt 0 0\nvt 1 0\nvt 0 1\n"
    "vn 0 0 1\n"
    "usemtl painted\n"
    "f 1/1/1 2/2/1 3/3/1\n";

std::string mtl_with_map(const std::string& map) { return "newmtl painted\nKd 0.5 0.5 0.5\nmap_Kd " + map + "\n"; }

TEST(TexturedModel, ObjTextureCoordinatesArePointedDownAndMapKdIsTheBaseColour) {
  TempDir dir;
  write_checker_png(dir / "checker.png");
  dir.write("m.mtl", mtl_with_map("checker.png"));
  const Model model = load_model(dir.write("tri.obj", kTexturedObj), dir.path());
  ASSERT_EQ(model.meshes.size(), 1u);
  const Mesh& mesh = model.meshes[0];
  ASSERT_EQ(mesh.uvs.size(), mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    // vt (s, t) at position (x, y): (0,0) at the origin, (1,0) at x = 1, (0,1) at y = 1; v = 1 - t.
    EXPECT_FLOAT_EQ(mesh.uvs[i].x, mesh.positions[i].x) << i;
    EXPECT_FLOAT_EQ(mesh.uvs[i].y, 1.0f - mesh.positions[i].y) << i;
  }
  const Material& m = model.materials.at(mesh.material);
  ASSERT_TRUE(m.textures);
  ASSERT_TRUE(m.textures->base_colour);
  const Texture& t = *m.textures->base_colour.texture;
  ASSERT_EQ(t.width(), 2);
  EXPECT_EQ(t.texel(0, 0, 0), glm::vec4(1, 0, 0, 1));  // top-left: red
  EXPECT_EQ(t.texel(0, 0, 1), glm::vec4(0, 0, 1, 1));  // bottom-left: blue
  // The factor times the texture: kd 0.5 over the red texel.
  Material scratch;
  const Material& at = material_at(m, glm::vec2(0.25f, 0.25f), 0.0f, scratch);
  EXPECT_EQ(at.diffuse, glm::vec3(0.5f, 0.0f, 0.0f));
  const Material plain;  // no textures: shaded as it is, not copied
  EXPECT_EQ(&material_at(plain, glm::vec2(0.25f), 0.0f, scratch), &plain);
}

TEST(TexturedModel, AMissingOrEscapingMapIsAnErrorNamingTheModelTheMaterialAndTheFile) {
  TempDir dir;
  fs::create_directories(dir / "root");
  write_checker_png(dir / "outside.png");
  dir.write("root/m.mtl", mtl_with_map("nowhere.png"));
  const fs::path obj = dir.write("root/tri.obj", kTexturedObj);
  try {
    load_model(obj, dir / "root");
    FAIL() << "loaded a model whose texture is missing";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("tri.obj"), std::string::npos) << what;
    EXPECT_NE(what.find("painted"), std::string::npos) << what;
    EXPECT_NE(what.find("nowhere.png"), std::string::npos) << what;
  }
  dir.write("root/m.mtl", mtl_with_map("../outside.png"));
  try {
    load_model(obj, dir / "root");
    FAIL() << "read a texture outside the asset root";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("outside"), std::string::npos) << what;
  }
}

// A hundred models (a job's hundred objects) naming one texture: one decode, one Texture in memory.
TEST(TexturedModel, AHundredModelsNamingOneTextureDecodeItOnce) {
  TempDir dir;
  write_checker_png(dir / "shared.png");
  dir.write("m.mtl", mtl_with_map("shared.png"));
  std::vector<Model> models;
  const std::uint64_t before = TextureCache::process().decodes();
  for (int i = 0; i < 100; ++i) {
    models.push_back(load_model(dir.write("tri" + std::to_string(i) + ".obj", kTexturedObj), dir.path()));
  }
  EXPECT_EQ(TextureCache::process().decodes() - before, 1u);
  std::set<const Texture*> distinct;
  for (const Model& m : models) distinct.insert(m.materials.at(m.meshes[0].material).textures->base_colour.texture.get());
  EXPECT_EQ(distinct.size(), 1u);
}

// The issue's figure, through a job as `farm render` builds it: a hundred objects, each its own
// model file, all naming one 4096x4096 texture. The texture is decoded once, every object's
// material points at that one copy, and rendering reads it without decoding it again.
TEST(TexturedModel, AHundredObjectJobSharingOne4096TextureDecodesItOnceAndHoldsOneCopy) {
  TempDir dir;
  constexpr int kSide = 4096;
  std::vector<std::uint8_t> pixels(std::size_t{kSide} * kSide * 3, 0);
  for (std::size_t i = 0; i < pixels.size(); i += 3) pixels[i] = ((i / 3 / 64) % 2) ? 255 : 0;
  write_rgb_png(dir / "shared.png", kSide, kSide, std::move(pixels));
  dir.write("m.mtl", mtl_with_map("shared.png"));
  nlohmann::json objects = nlohmann::json::array();
  for (int i = 0; i < 100; ++i) {
    const std::string name = "tri" + std::to_string(i) + ".obj";
    dir.write(name, kTexturedObj);
    objects.push_back({{"file", name}, {"translate", {0.01 * i, 0, 0}}});
  }
  const nlohmann::json doc = {{"version", 1},
                              {"scene", {{"objects", objects}, {"camera", {{"position", {0.5, 0.5, 3}}, {"target", {0.5, 0.5, 0}}}}}},
                              {"render", {{"engine", "raster"}, {"width", 16}, {"height", 16}}}};
  const std::uint64_t before = TextureCache::process().decodes();
  const Job job = parse_job(doc.dump(), dir / "job.json");
  const PreparedScene scene(build_scene(job));
  EXPECT_EQ(TextureCache::process().decodes() - before, 1u);
  std::set<const Texture*> distinct;
  for (const SceneObject& object : scene.scene().objects) {
    for (const Material& m : object.materials) {
      if (m.textures && m.textures->base_colour) distinct.insert(m.textures->base_colour.texture.get());
    }
  }
  ASSERT_EQ(distinct.size(), 1u);
  const Texture& texture = **distinct.begin();
  EXPECT_EQ(texture.width(), kSide);
  EXPECT_GE(texture.memory_bytes(), std::size_t{kSide} * kSide * sizeof(glm::vec4));  // one real copy
  const TileBuffer image = render_frame(scene, job.render);
  EXPECT_EQ(TextureCache::process().decodes() - before, 1u);
  bool red = false, dark = false;  // both stripes are seen, so the texture was read
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) (image.rgba(x, y).x > 0.05f ? red : dark) = true;
  }
  EXPECT_TRUE(red && dark);
}

// PLY's per-vertex u, v (and s, t) are its texture coordinates, v pointing up as in OBJ.
TEST(TexturedModel, PlyTextureCoordinatesAreReadFromUvAndSt) {
  TempDir dir;
  for (const char* names : {"u v", "s t"}) {
    const std::string u(1, names[0]), v(1, names[2]);
    const fs::path ply = dir.write("tri_" + u + ".ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                                                         "property float x\nproperty float y\nproperty float z\n"
                                                         "property float " + u + "\nproperty float " + v + "\n"
                                                         "element face 1\nproperty list uchar int vertex_indices\n"
                                                         "end_header\n0 0 0 0 0.25\n1 0 0 1 0.25\n0 1 0 0 1\n3 0 1 2\n");
    const Model model = load_model(ply, dir.path());
    ASSERT_EQ(model.meshes.size(), 1u) << names;
    const Mesh& mesh = model.meshes[0];
    ASSERT_EQ(mesh.uvs.size(), mesh.positions.size()) << names;
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      const bool top = mesh.positions[i].y == 1.0f;
      EXPECT_FLOAT_EQ(mesh.uvs[i].x, mesh.positions[i].x) << names << " " << i;
      EXPECT_FLOAT_EQ(mesh.uvs[i].y, top ? 0.0f : 0.75f) << names << " " << i;
    }
  }
}

// A glTF quad with TEXCOORD_0 and a base colour texture whose sampler clamps, moved by
// KHR_texture_transform.
TEST(TexturedModel, GltfReadsTexcoordsTheSamplerAndTheTextureTransform) {
  TempDir dir;
  write_checker_png(dir / "checker.png");
  const fs::path gltf = write_textured_triangle(dir, "quad.gltf", R"(
    "extensionsUsed": ["KHR_texture_transform"],
    "images": [{"uri": "checker.png"}],
    "samplers": [{"wrapS": 33071, "wrapT": 33648, "magFilter": 9728}],
    "textures": [{"source": 0, "sampler": 0}],
    "materials": [{"name": "painted", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
      "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [0.5, 1]}}}}}])");
  const Model model = load_model(gltf, dir.path());
  ASSERT_EQ(model.meshes.size(), 1u);
  const Mesh& mesh = model.meshes[0];
  ASSERT_EQ(mesh.uvs.size(), 3u);
  // glTF's v already points down: kept as written.
  EXPECT_EQ(mesh.uvs[0], glm::vec2(0.0f, 1.0f));
  EXPECT_EQ(mesh.uvs[1], glm::vec2(1.0f, 1.0f));
  const Material& m = model.materials.at(mesh.material);
  ASSERT_TRUE(m.textures && m.textures->base_colour);
  const TextureSlot& slot = m.textures->base_colour;
  EXPECT_EQ(slot.sampler.wrap_u, TextureWrap::ClampToEdge);
  EXPECT_EQ(slot.sampler.wrap_v, TextureWrap::MirroredRepeat);
  EXPECT_EQ(slot.sampler.magnify, TextureFilter::Nearest);
  // uv (0.1, 0.2) moves to (0.5 + 0.05, 0.2): the top-right texel, green.
  EXPECT_EQ(glm::vec3(slot.sample(glm::vec2(0.1f, 0.2f), 0.0f)), glm::vec3(0, 1, 0));
  // Clamped in u: far right stays in the right column; mirrored in v: v = 1.2 reads as 0.8 (bottom).
  EXPECT_EQ(glm::vec3(slot.sample(glm::vec2(3.0f, 1.2f), 0.0f)), glm::vec3(1, 1, 1));
}

// glTF's metal-roughness and occlusion textures: data, read as stored. One 1x1 texture holds
// occlusion 64 (red), roughness 128 (green) and metalness 255 (blue), as glTF packs them; the
// material's factors multiply them, and the product is mapped to Phong at each point as the
// loader maps plain factors. A job's override of kd leaves the base colour texture multiplying it.
TEST(TexturedModel, GltfMetalRoughnessAndOcclusionTexturesAreMappedAtEachPoint) {
  TempDir dir;
  write_checker_png(dir / "checker.png");
  write_rgb_png(dir / "orm.png", 1, 1, {64, 128, 255});
  const fs::path gltf = write_textured_triangle(dir, "pbr.gltf", R"(
    "images": [{"uri": "checker.png"}, {"uri": "orm.png"}],
    "textures": [{"source": 0}, {"source": 1}],
    "materials": [{"name": "worn", "occlusionTexture": {"index": 1, "strength": 0.5},
      "pbrMetallicRoughness": {"baseColorFactor": [0.5, 1, 1, 1], "metallicFactor": 0.5, "roughnessFactor": 0.8,
        "baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 1}}}])");
  const Model model = load_model(gltf, dir.path());
  const Material& m = model.materials.at(model.meshes[0].material);
  ASSERT_TRUE(m.textures && m.textures->metal_roughness && m.textures->occlusion);
  Material scratch;
  // The top-left texel is red: base colour (0.5, 0, 0); metalness 0.5 x 1; roughness 0.8 x 128/255.
  const Material& at = material_at(m, glm::vec2(0.25f, 0.25f), 0.0f, scratch);
  Material expected;
  set_metal_roughness(expected, glm::vec3(0.5f, 0.0f, 0.0f), 0.5f, 0.8f * (128.0f / 255.0f));
  EXPECT_EQ(at.diffuse, expected.diffuse);
  EXPECT_EQ(at.specular, expected.specular);
  EXPECT_FLOAT_EQ(at.shininess, expected.shininess);
  EXPECT_NE(at.shininess, m.shininess);  // the texture's roughness moved it from the factor's
  // The path tracer's values: the same product, unmapped.
  ASSERT_TRUE(at.metal_roughness);
  EXPECT_EQ(at.metal_roughness->base_colour, glm::vec3(0.5f, 0.0f, 0.0f));
  EXPECT_FLOAT_EQ(at.metal_roughness->metallic, 0.5f);
  EXPECT_FLOAT_EQ(at.metal_roughness->roughness, 0.8f * (128.0f / 255.0f));
  // Occlusion 64/255 at strength 0.5: the ambient term keeps 1 + 0.5 (0.251 - 1) of itself.
  EXPECT_FLOAT_EQ(at.ambient.x, m.ambient.x * (1.0f + 0.5f * (64.0f / 255.0f - 1.0f)));

  // A job that gives kd: the texture multiplies what it gave.
  Material overridden = m;
  MaterialOverride give;
  give.diffuse = glm::vec3(0.25f);
  give.apply_to(overridden);
  const Material& phong = material_at(overridden, glm::vec2(0.25f, 0.25f), 0.0f, scratch);
  EXPECT_EQ(phong.diffuse, glm::vec3(0.25f, 0.0f, 0.0f));
  EXPECT_FALSE(phong.metal_roughness);  // a Phong material now, in the path tracer too
  EXPECT_TRUE(m.metal_roughness);       // the model's own material is left as it was
}

// glTF's alphaMode, alphaCutoff and the base colour's alpha: a MASK material's coverage is the
// factor's alpha times the texture's (the checker's RGB PNG has alpha 1), and it is cut out
// below the cutoff; an OPAQUE one never, whatever its alpha.
TEST(TexturedModel, GltfAlphaModeCutoffAndBaseColourAlphaAreRead) {
  TempDir dir;
  write_checker_png(dir / "checker.png");
  const fs::path gltf = write_textured_triangle(dir, "cut.gltf", R"(
    "images": [{"uri": "checker.png"}],
    "textures": [{"source": 0}],
    "materials": [{"name": "lace", "alphaMode": "MASK", "alphaCutoff": 0.25,
      "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.2], "baseColorTexture": {"index": 0}}},
      {"name": "veil", "alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.6]}},
      {"name": "plain", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.1]}}])");
  const Model model = load_model(gltf, dir.path());
  ASSERT_EQ(model.materials.size(), 3u);
  const Material &lace = model.materials[0], &veil = model.materials[1], &plain = model.materials[2];
  EXPECT_EQ(lace.alpha_mode, AlphaMode::Mask);
  EXPECT_FLOAT_EQ(lace.alpha_cutoff, 0.25f);
  EXPECT_FLOAT_EQ(coverage_at(lace, glm::vec2(0.3f, 0.3f)), 0.2f);
  EXPECT_TRUE(cut_out(lace, glm::vec2(0.3f, 0.3f), 0.0f));
  EXPECT_EQ(veil.alpha_mode, AlphaMode::Blend);
  EXPECT_FALSE(cut_out(veil, glm::vec2(0.0f), 0.59f));
  EXPECT_TRUE(cut_out(veil, glm::vec2(0.0f), 0.61f));
  EXPECT_EQ(plain.alpha_mode, AlphaMode::Opaque);
  EXPECT_FALSE(cut_out(plain, glm::vec2(0.0f), 0.99f));
}

// MTL's map_d, a dissolve texture, is the surface's coverage (its red; 1 opaque), blended: a
// texel of 0 lets every ray through, one of 255 none.
TEST(TexturedModel, AnMtlDissolveMapIsTheSurfacesCoverage) {
  TempDir dir;
  write_rgb_png(dir / "holes.png", 2, 1, {0, 0, 0, 255, 255, 255});
  dir.write("m.mtl", "newmtl painted\nKd 0.5 0.5 0.5\nmap_d holes.png\n");
  const Model model = load_model(dir.write("tri.obj", kTexturedObj), dir.path());
  const Material& m = model.materials.at(model.meshes[0].material);
  ASSERT_TRUE(m.textures && m.textures->opacity);
  EXPECT_EQ(m.alpha_mode, AlphaMode::Blend);
  // At the texels' centres (bilinear, repeating: elsewhere the two mix).
  EXPECT_FLOAT_EQ(coverage_at(m, glm::vec2(0.25f, 0.5f)), 0.0f);
  EXPECT_FLOAT_EQ(coverage_at(m, glm::vec2(0.75f, 0.5f)), 1.0f);
  EXPECT_TRUE(cut_out(m, glm::vec2(0.25f, 0.5f), 0.0f));
  EXPECT_FALSE(cut_out(m, glm::vec2(0.75f, 0.5f), 0.999f));
}

// MTL's bump (map_Bump) holding a normal map, as Blender's OBJ exporter writes one, is read as
// the normal map; one that is missing is left out, as before bump was looked at.
TEST(TexturedModel, AnMtlBumpHoldingANormalMapIsReadAsOne) {
  TempDir dir;
  write_rgb_png(dir / "normal.png", 1, 1, {128, 128, 255});
  dir.write("m.mtl", "newmtl painted\nKd 0.5 0.5 0.5\nmap_Bump -bm 1.0 normal.png\n");
  const Model bumped = load_model(dir.write("tri.obj", kTexturedObj), dir.path());
  const Material& b = bumped.materials.at(bumped.meshes[0].material);
  ASSERT_TRUE(b.textures && b.textures->normal);
  EXPECT_EQ(bumped.meshes[0].tangents.size(), bumped.meshes[0].positions.size());  // a frame to read it in
  EXPECT_EQ(b.textures->normal.texture->texel(0, 0, 0), glm::vec4(128.0f / 255.0f, 128.0f / 255.0f, 1.0f, 1.0f))
      << "read as stored, not made from heights";
  dir.write("m.mtl", "newmtl painted\nKd 0.5 0.5 0.5\nbump missing.png\n");
  const Model missing = load_model(dir.path() / "tri.obj", dir.path());
  EXPECT_FALSE(missing.materials.at(missing.meshes[0].material).textures);
}

// A height map in MTL's bump bends the shading normal away from the slope, by the slope its
// heights times -bm make in uv units: on this triangle u runs along +x and v along -y, so a ramp
// rising to the right (u) tilts the normal towards -x and one rising down the image (v, towards
// -y) towards +y. 16 texels from 0 to 240 of 255: a slope of 0.5 * 16 * 16 / 255 per uv unit.
TEST(TexturedModel, AnMtlBumpHoldingAHeightMapBendsTheNormalByItsSlopeTimesBm) {
  TempDir dir;
  std::vector<std::uint8_t> along_u, along_v;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      for (int c = 0; c < 3; ++c) {
        along_u.push_back(static_cast<std::uint8_t>(16 * x));
        along_v.push_back(static_cast<std::uint8_t>(16 * y));
      }
  write_rgb_png(dir / "along_u.png", 16, 16, along_u);
  write_rgb_png(dir / "along_v.png", 16, 16, along_v);
  dir.write("tri.obj", kTexturedObj);
  const float slope = 0.5f * 16.0f * 16.0f / 255.0f;
  const std::uint64_t decodes_before = TextureCache::process().decodes();
  for (const auto& [map, expected] : {std::pair{"along_u.png", glm::vec3(-slope, 0.0f, 1.0f)},
                                      std::pair{"along_v.png", glm::vec3(0.0f, slope, 1.0f)}}) {
    dir.write("m.mtl", std::string("newmtl painted\nKd 0.5 0.5 0.5\nbump -bm 0.5 ") + map + "\n");
    const Model model = load_model(dir.path() / "tri.obj", dir.path());
    const Mesh& mesh = model.meshes[0];
    const Material& m = model.materials.at(mesh.material);
    ASSERT_TRUE(m.textures && m.textures->normal) << map;
    ASSERT_EQ(mesh.tangents.size(), mesh.positions.size());
    // Away from the edges, where the repeating map's slope jumps back from 240 to 0.
    const glm::vec3 n = mapped_normal(*m.textures, glm::vec2(0.3f, 0.4f), glm::vec3(0, 0, 1), mesh.tangents[0]);
    const glm::vec3 want = glm::normalize(expected);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(n[c], want[c], 1e-5f) << map << " component " << c;
  }
  // Each file decoded once, and its normal map made once.
  EXPECT_EQ(TextureCache::process().decodes() - decodes_before, 4u);
}

// One set of texture coordinates is read: a base colour map on TEXCOORD_1 is refused with the
// material and the slot named, an occlusion map there (a lightmap's, typically) left out.
TEST(TexturedModel, AGltfMapOnASecondSetOfTextureCoordinatesIsRefusedUnlessItIsOcclusion) {
  TempDir dir;
  write_checker_png(dir / "checker.png");
  const std::string images = R"("images": [{"uri": "checker.png"}], "textures": [{"source": 0}],)";
  const fs::path second = write_textured_triangle(dir, "uv1.gltf", images + R"(
    "materials": [{"name": "decal", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}}}])");
  try {
    load_model(second, dir.path());
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("material 'decal' baseColorTexture: reads TEXCOORD_1"), std::string::npos)
        << e.what();
  }
  const fs::path lightmapped = write_textured_triangle(dir, "ao.gltf", images + R"(
    "materials": [{"name": "baked", "occlusionTexture": {"index": 0, "texCoord": 1},
      "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])");
  const Model model = load_model(lightmapped, dir.path());
  ASSERT_TRUE(model.materials[0].textures);
  EXPECT_TRUE(model.materials[0].textures->base_colour);
  EXPECT_FALSE(model.materials[0].textures->occlusion);
}

// A glTF normal map without TANGENTs: the loader makes the tangent frame from the uvs (u grows
// along +x, v falls along +y on this triangle), and keeps the map's scale.
TEST(TexturedModel, AGltfNormalMapGetsTangentsFromTheUvsWhenTheFileHasNone) {
  TempDir dir;
  write_rgb_png(dir / "normal.png", 1, 1, {128, 128, 255});
  const fs::path gltf = write_textured_triangle(dir, "bumpy.gltf", R"(
    "images": [{"uri": "normal.png"}],
    "textures": [{"source": 0}],
    "materials": [{"name": "bumpy", "normalTexture": {"index": 0, "scale": 0.5}}])");
  const Model model = load_model(gltf, dir.path());
  const Mesh& mesh = model.meshes[0];
  const Material& m = model.materials.at(mesh.material);
  ASSERT_TRUE(m.textures && m.textures->normal);
  EXPECT_EQ(m.textures->normal_scale, 0.5f);
  EXPECT_EQ(m.textures->normal.texture->texel(0, 0, 0).x, 128.0f / 255.0f);  // data: not sRGB-decoded
  ASSERT_EQ(mesh.tangents.size(), mesh.positions.size());
  for (const glm::vec4& t : mesh.tangents) EXPECT_EQ(t, glm::vec4(1, 0, 0, 1));
}

std::string read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string base64(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto byte = [&](std::size_t i) { return i < bytes.size() ? static_cast<std::uint8_t>(bytes[i]) : 0u; };
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t v = byte(i) << 16 | byte(i + 1) << 8 | byte(i + 2);
    const std::size_t present = std::min<std::size_t>(3, bytes.size() - i);  // bytes in this group
    for (std::size_t k = 0; k < 4; ++k) out += k <= present ? kAlphabet[(v >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

// A triangle whose material's base colour is the checker, its image inside the file: a .glb
// whose binary chunk holds the PNG (a buffer view), and a .gltf whose image is a data: URI. Each
// is decoded once, keyed by its model file, and reads as the same texels as the file beside it.
TEST(TexturedModel, GltfImagesEmbeddedInTheFileAreDecodedFromTheirBytes) {
  TempDir dir;
  write_checker_png(dir / "checker.png");
  const std::string png = read_bytes(dir / "checker.png");
  std::string bin(reinterpret_cast<const char*>(kTriangleData), sizeof kTriangleData);
  bin += png;
  while (bin.size() % 4 != 0) bin += '\0';
  const auto document = [&](const std::string& buffer, const std::string& image) {
    return R"({"asset": {"version": "2.0"}, )" + buffer + R"(,
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24},
                      {"buffer": 0, "byteOffset": 60, "byteLength": )" + std::to_string(png.size()) + R"(}],
      "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
        {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
      "images": [)" + image + R"(],
      "textures": [{"source": 0}],
      "materials": [{"name": "painted", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
      "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})";
  };
  // .glb: header, JSON chunk (padded with spaces), BIN chunk.
  std::string json = document(R"("buffers": [{"byteLength": )" + std::to_string(bin.size()) + "}]",
                              R"({"bufferView": 2, "mimeType": "image/png"})");
  while (json.size() % 4 != 0) json += ' ';
  const auto u32 = [](std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  const std::string glb = "glTF" + u32(2) + u32(static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size())) +
                          u32(static_cast<std::uint32_t>(json.size())) + "JSON" + json +
                          u32(static_cast<std::uint32_t>(bin.size())) + std::string("BIN\0", 4) + bin;
  const fs::path glb_file = dir.write("embedded.glb", glb);
  // .gltf: the same buffer as a data: URI, and the image as another.
  const fs::path gltf_file = dir.write(
      "embedded.gltf",
      document(R"("buffers": [{"byteLength": )" + std::to_string(bin.size()) +
                   R"(, "uri": "data:application/octet-stream;base64,)" + base64(bin) + R"("}])",
               R"({"uri": "data:image/png;base64,)" + base64(png) + R"("})"));

  const std::uint64_t before = TextureCache::process().decodes();
  std::vector<Model> held;
  for (const fs::path& file : {glb_file, gltf_file, glb_file}) {
    held.push_back(load_model(file, dir.path()));
    const Model& model = held.back();
    ASSERT_EQ(model.meshes.size(), 1u) << file;
    const Material& m = model.materials.at(model.meshes[0].material);
    ASSERT_TRUE(m.textures && m.textures->base_colour) << file;
    const Texture& t = *m.textures->base_colour.texture;
    ASSERT_EQ(t.width(), 2) << file;
    EXPECT_EQ(t.texel(0, 0, 0), glm::vec4(1, 0, 0, 1)) << file;  // red, top-left
    EXPECT_EQ(t.texel(0, 1, 1), glm::vec4(1, 1, 1, 1)) << file;  // white, bottom-right
  }
  // One decode per model file: the .glb loaded twice shares its texture.
  EXPECT_EQ(TextureCache::process().decodes() - before, 2u);
  EXPECT_EQ(held[0].materials[0].textures->base_colour.texture, held[2].materials[0].textures->base_colour.texture);
  // An embedded image that is no PNG or JPEG is an error naming the model and the material.
  std::string broken = glb;
  broken.replace(broken.find("\x89PNG"), 4, "GIF8");
  try {
    load_model(dir.write("broken.glb", broken), dir.path());
    FAIL() << "decoded a GIF header as a texture";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("broken.glb"), std::string::npos) << what;
    EXPECT_NE(what.find("painted"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace farm
