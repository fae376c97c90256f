// COLLADA, OBJ and PLY through Assimp. The node hierarchy is baked into the meshes, so the model
// comes out in the file's root space; Assimp's COLLADA importer already rotates Z_UP files to +Y
// up through the root node's transform, which the bake picks up like any other node transform.
#include <assimp/ObjMaterial.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <exception>
#include <glm/geometric.hpp>
#include <glm/gtc/constants.hpp>
#include <glm/trigonometric.hpp>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "renderer/loaders/confined_io_system.h"
#include "renderer/loaders/join_identical_vertices.h"
#include "renderer/loaders/loaders.h"
#include "renderer/texture/material_textures.h"
#include "renderer/texture/texture_cache.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

glm::vec3 to_glm(const aiVector3D& v) { return {v.x, v.y, v.z}; }
glm::vec3 to_glm(const aiColor3D& c) { return {c.r, c.g, c.b}; }

glm::mat4 to_glm(const aiMatrix4x4& m) {
  // Assimp stores rows (a1..a4 is the first row); GLM indexes [column][row].
  const ai_real* rows = &m.a1;
  glm::mat4 out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out[c][r] = static_cast<float>(rows[4 * r + c]);
  return out;
}

// A texture a material names for `type` (MTL's map_Kd, map_Ks, map_Ke; COLLADA's <texture>),
// confined to the model's root, with the sampler its wrap modes give; none when it names none,
// or one embedded in the file ("*0"), which these formats do not use.
struct NamedTexture {
  std::filesystem::path resolved;
  TextureSampler sampler;
  std::string material;  // for messages
};

std::optional<NamedTexture> named_texture(const ModelFile& file, const aiMaterial& in, aiTextureType type) {
  aiString path;
  aiTextureMapMode modes[2] = {aiTextureMapMode_Wrap, aiTextureMapMode_Wrap};
  if (in.GetTexture(type, 0, &path, nullptr, nullptr, nullptr, nullptr, modes) != AI_SUCCESS) return std::nullopt;
  const std::string written = path.C_Str();
  if (written.empty() || written[0] == '*') return std::nullopt;
  const ConfinedFile confined = confine_loader_path(file, written);
  const std::string material = in.GetName().length > 0 ? in.GetName().C_Str() : "(unnamed)";
  if (!confined.allowed()) {
    throw InputError(file.name.string() + ": material '" + material + "': texture '" + written + "': " +
                     (confined.reason.empty() ? "no such file" : confined.reason));
  }
  const auto wrap = [](aiTextureMapMode mode) {
    return mode == aiTextureMapMode_Clamp ? TextureWrap::ClampToEdge
           : mode == aiTextureMapMode_Mirror ? TextureWrap::MirroredRepeat
                                              : TextureWrap::Repeat;
  };
  NamedTexture named{confined.resolved, {}, material};
  named.sampler.wrap_u = wrap(modes[0]);
  named.sampler.wrap_v = wrap(modes[1]);
  return named;
}

// `decode` run for `named`, its failure said as the material's.
template <typename Decode>
std::shared_ptr<const Texture> decoded(const ModelFile& file, const NamedTexture& named, Decode&& decode) {
  try {
    return decode();
  } catch (const InputError& e) {
    throw InputError(file.name.string() + ": material '" + named.material + "': " + e.what());
  }
}

// The texture a material names for `type`, decoded through the process's cache; an empty slot
// when it names none.
TextureSlot texture_slot(const ModelFile& file, const aiMaterial& in, aiTextureType type, TextureColourSpace space) {
  const std::optional<NamedTexture> named = named_texture(file, in, type);
  if (!named) return {};
  TextureSlot slot;
  slot.sampler = named->sampler;
  slot.texture = decoded(file, *named, [&] { return TextureCache::process().get(named->resolved, space); });
  return slot;
}

// Whether a texture's mean (its last, 1x1 mip level) is a tangent-space normal map's: pointing
// mostly out of the surface, leaning little either way.
bool looks_like_normal_map(const Texture& texture) {
  const glm::vec4& mean = texture.texel(texture.levels() - 1, 0, 0);
  return mean.z > 0.7f && std::fabs(mean.x - 0.5f) < 0.15f && std::fabs(mean.y - 0.5f) < 0.15f;
}

// MTL's bump (map_Bump) as a normal map. It is a height map by the format's definition, turned
// into the normal map it describes, its heights times -bm (normal_map_from_height); but
// exporters such as Blender's write their normal maps there: an image whose mean is a normal
// map's (blue near 1, red and green near a half) is read as one. A bump map that cannot be read
// (missing, outside the root, not an image) is left out, as it always was, rather than failing
// the model.
TextureSlot bump_slot(const ModelFile& file, const aiMaterial& in) {
  try {
    const std::optional<NamedTexture> named = named_texture(file, in, aiTextureType_HEIGHT);
    if (!named) return {};
    TextureSlot slot;
    slot.sampler = named->sampler;
    TextureCache& cache = TextureCache::process();
    slot.texture = decoded(file, *named, [&] { return cache.get(named->resolved, TextureColourSpace::Linear); });
    if (looks_like_normal_map(*slot.texture)) return slot;
    ai_real scale = 1;
    if (in.Get(AI_MATKEY_OBJ_BUMPMULT_HEIGHT(0), scale) != AI_SUCCESS || !std::isfinite(scale)) scale = 1;
    slot.texture = cache.get_normals_from_height(named->resolved, *slot.texture, static_cast<float>(scale),
                                                 slot.sampler.wrap_u, slot.sampler.wrap_v);
    return slot;
  } catch (const InputError&) {
    return {};
  }
}

Material convert_material(const ModelFile& file, const aiMaterial& in) {
  Material m;
  aiString name;
  if (in.Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length > 0) m.name = name.C_Str();

  // Keys the file leaves out (or gives as nonsense) keep the Material defaults.
  auto colour = [&](const char* key, unsigned type, unsigned index, glm::vec3& out) {
    aiColor3D c;
    if (in.Get(key, type, index, c) == AI_SUCCESS && all_finite(to_glm(c))) out = to_glm(c);
  };
  auto scalar = [&](const char* key, unsigned type, unsigned index, float& out) {
    ai_real v = 0;
    if (in.Get(key, type, index, v) == AI_SUCCESS && std::isfinite(v)) {
      out = static_cast<float>(v);
      return true;
    }
    return false;
  };
  colour(AI_MATKEY_COLOR_AMBIENT, m.ambient);
  colour(AI_MATKEY_COLOR_DIFFUSE, m.diffuse);
  colour(AI_MATKEY_COLOR_SPECULAR, m.specular);
  // MTL and COLLADA have no way to say which side of a surface emits: front only, as
  // emission_sides defaults (a job's material override can say "both").
  colour(AI_MATKEY_COLOR_EMISSIVE, m.emission);
  scalar(AI_MATKEY_SHININESS, m.shininess);
  scalar(AI_MATKEY_REFRACTI, m.ior);
  float opacity = 1.0f;
  if (scalar(AI_MATKEY_OPACITY, opacity)) m.transmission = 1.0f - std::clamp(opacity, 0.0f, 1.0f);

  MaterialTextures textures;
  textures.base_colour = texture_slot(file, in, aiTextureType_DIFFUSE, TextureColourSpace::Srgb);
  textures.specular = texture_slot(file, in, aiTextureType_SPECULAR, TextureColourSpace::Srgb);
  textures.emission = texture_slot(file, in, aiTextureType_EMISSIVE, TextureColourSpace::Srgb);
  // MTL's norm, a normal map; else its bump (map_Bump).
  textures.normal = texture_slot(file, in, aiTextureType_NORMALS, TextureColourSpace::Linear);
  if (!textures.normal) textures.normal = bump_slot(file, in);
  // MTL's map_d, a dissolve texture: the surface covers what it says, partly where it is grey
  // (blended; a map of 0s and 1s, the usual cut-out leaf, cuts exactly).
  textures.opacity = texture_slot(file, in, aiTextureType_OPACITY, TextureColourSpace::Linear);
  if (textures.opacity) m.alpha_mode = AlphaMode::Blend;
  if (textures.base_colour || textures.specular || textures.emission || textures.normal || textures.opacity) {
    m.textures = std::make_shared<const MaterialTextures>(std::move(textures));
  }
  return m;
}

Mesh convert_mesh(const aiMesh& in, const std::string& node_name) {
  Mesh out;
  out.name = in.mName.length > 0 ? in.mName.C_Str() : node_name;
  out.material = in.mMaterialIndex;
  out.positions.reserve(in.mNumVertices);
  for (unsigned i = 0; i < in.mNumVertices; ++i) out.positions.push_back(to_glm(in.mVertices[i]));
  if (in.HasNormals()) {
    out.normals.reserve(in.mNumVertices);
    for (unsigned i = 0; i < in.mNumVertices; ++i) out.normals.push_back(to_glm(in.mNormals[i]));
  }
  if (in.HasTextureCoords(0)) {
    // Assimp keeps the file's v, which points up in these formats; ours points down.
    out.uvs.reserve(in.mNumVertices);
    for (unsigned i = 0; i < in.mNumVertices; ++i) {
      const aiVector3D& t = in.mTextureCoords[0][i];
      out.uvs.emplace_back(t.x, 1.0f - t.y);
    }
  }
  // SortByPType already moved points and lines out; keep exactly the triangles.
  for (unsigned f = 0; f < in.mNumFaces; ++f) {
    const aiFace& face = in.mFaces[f];
    if (face.mNumIndices != 3) continue;
    out.triangles.emplace_back(face.mIndices[0], face.mIndices[1], face.mIndices[2]);
  }
  return out;
}

// aiCamera's documentation calls mHorizontalFOV half the angle, but Assimp 5.2's COLLADA importer
// (the only one of ours that yields cameras) stores the file's full <xfov>: cow.dae's 39.6 degrees
// comes back as 0.691 rad. So it is treated as the full horizontal angle here.
std::optional<Camera> convert_camera(const aiCamera& in, const glm::mat4& node_to_root) {
  Camera cam;
  const glm::mat3 linear(node_to_root);
  const glm::vec3 forward = linear * to_glm(in.mLookAt);
  const glm::vec3 up = linear * to_glm(in.mUp);
  if (!(glm::length(forward) > 0.0f) || !(glm::length(up) > 0.0f)) return std::nullopt;
  cam.position = glm::vec3(node_to_root * glm::vec4(to_glm(in.mPosition), 1.0f));
  cam.target = cam.position + glm::normalize(forward);
  cam.up = glm::normalize(up);
  if (!all_finite(cam.position) || !all_finite(cam.target) || !all_finite(cam.up)) {
    return std::nullopt;
  }

  const float horizontal = in.mHorizontalFOV;
  if (in.mAspect > 0.0f && std::isfinite(in.mAspect)) cam.aspect = in.mAspect;
  if (horizontal > 0.0f && horizontal < glm::pi<float>()) {
    const float vertical =
        cam.aspect ? 2.0f * std::atan(std::tan(0.5f * horizontal) / *cam.aspect) : horizontal;
    cam.fov_y_degrees = glm::degrees(vertical);
  }
  if (in.mClipPlaneNear > 0.0f && in.mClipPlaneFar > in.mClipPlaneNear &&
      std::isfinite(in.mClipPlaneFar)) {
    cam.near = in.mClipPlaneNear;
    cam.far = in.mClipPlaneFar;
  }
  return cam;
}

// Ambient and area lights have no counterpart among our delta lights and are left out.
std::optional<Light> convert_light(const aiLight& in, const glm::mat4& node_to_root) {
  Light light;
  light.intensity = to_glm(in.mColorDiffuse);
  switch (in.mType) {
    case aiLightSource_POINT:
    case aiLightSource_SPOT:  // no cone in our model: the spot lights everything around it
      light.kind = Light::Kind::Point;
      light.position = glm::vec3(node_to_root * glm::vec4(to_glm(in.mPosition), 1.0f));
      if (!all_finite(light.position)) return std::nullopt;
      break;
    case aiLightSource_DIRECTIONAL: {
      const glm::vec3 d = glm::mat3(node_to_root) * to_glm(in.mDirection);
      if (!(glm::length(d) > 0.0f) || !all_finite(d)) return std::nullopt;
      light.kind = Light::Kind::Directional;
      light.direction = glm::normalize(d);
      break;
    }
    default:
      return std::nullopt;
  }
  if (!all_finite(light.intensity)) return std::nullopt;
  return light;
}

// What Assimp's post-processing trusts of an importer's meshes without looking: every face has
// indices, each of them names a vertex, and mPrimitiveTypes says which face sizes occur. A
// malformed file can break any of them (a PLY whose face list runs into its vertex data has faces
// of no indices, flagged as polygons), and Triangulate then aborts the process on an assertion
// (`numOut != pMesh->mNumFaces`) instead of failing. So the meshes are checked here between the
// import and the post-processing, and the flags are recomputed from the faces themselves.
void check_imported_meshes(aiScene& scene, const std::string& name) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    aiMesh& mesh = *scene.mMeshes[m];
    unsigned types = 0;
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices == 0 || face.mIndices == nullptr) {
        throw InputError(name + ": mesh " + std::to_string(m) + ", face " + std::to_string(f) +
                         ": a face with no vertices");
      }
      for (unsigned i = 0; i < face.mNumIndices; ++i) {
        if (face.mIndices[i] >= mesh.mNumVertices) {
          throw InputError(name + ": mesh " + std::to_string(m) + ", face " + std::to_string(f) +
                           ": vertex index " + std::to_string(face.mIndices[i]) + " of " +
                           std::to_string(mesh.mNumVertices) + " vertices");
        }
      }
      types |= face.mNumIndices == 1   ? aiPrimitiveType_POINT
               : face.mNumIndices == 2 ? aiPrimitiveType_LINE
               : face.mNumIndices == 3 ? aiPrimitiveType_TRIANGLE
                                       : aiPrimitiveType_POLYGON;
    }
    mesh.mPrimitiveTypes = types;
  }
}

}  // namespace

Model load_with_assimp(const ModelFile& file) {
  const std::string name = file.name.string();
  Assimp::Importer importer;
  // Owned by the importer, which outlives every use of it here.
  auto* io = new ConfinedIOSystem(file);
  importer.SetIOHandler(io);
  // Points and lines cannot be rendered as surfaces; drop them instead of keeping split meshes.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // FindDegenerates/FindInvalidData are left out on purpose: they change triangle counts.
  // Import and post-processing are two calls, so that the imported meshes are checked between
  // them (check_imported_meshes).
  // Identical vertices are joined by join_identical_vertices afterwards, as Assimp's own step
  // would have joined them (last of these in its order), in a quarter of its time.
  constexpr unsigned kPostProcess = aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure;
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(file.file.resolved.string(), aiProcess_ValidateDataStructure);
    // Before anything else: the importer may have carried on without the file (an OBJ does
    // without its material library), and a model that names a file it may not read is refused.
    if (!io->refusal().empty()) throw InputError(name + ": " + io->refusal());
    if (scene == nullptr) throw InputError(name + ": " + importer.GetErrorString());
    // The importer's own scene, not yet handed out: Assimp's post-processing steps rewrite it in
    // place the same way.
    check_imported_meshes(const_cast<aiScene&>(*scene), name);
    scene = importer.ApplyPostProcessing(kPostProcess);
    if (scene != nullptr) {
      for (unsigned m = 0; m < scene->mNumMeshes; ++m) join_identical_vertices(*scene->mMeshes[m]);
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {  // Assimp catches its own; this is for allocation failures
    throw InputError(name + ": " + e.what());
  }
  if (scene == nullptr) throw InputError(name + ": " + importer.GetErrorString());
  if (scene->mRootNode == nullptr) throw InputError(name + ": the file has no scene hierarchy");

  Model model;
  model.source = file.name;
  for (unsigned i = 0; i < scene->mNumMaterials; ++i) {
    model.materials.push_back(convert_material(file, *scene->mMaterials[i]));
  }

  // Depth-first walk with an explicit stack: a hostile file cannot exhaust the call stack.
  std::map<std::string, glm::mat4> node_to_root_by_name;
  std::vector<std::pair<const aiNode*, glm::mat4>> stack{{scene->mRootNode, glm::mat4(1.0f)}};
  while (!stack.empty()) {
    const auto [node, parent_to_root] = stack.back();
    stack.pop_back();
    const glm::mat4 node_to_root = parent_to_root * to_glm(node->mTransformation);
    node_to_root_by_name.emplace(node->mName.C_Str(), node_to_root);
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      const unsigned index = node->mMeshes[i];
      if (index >= scene->mNumMeshes) throw InputError(name + ": node refers to a missing mesh");
      Mesh mesh = convert_mesh(*scene->mMeshes[index], node->mName.C_Str());
      bake_node_transform(mesh, node_to_root);
      model.meshes.push_back(std::move(mesh));
    }
    for (unsigned i = node->mNumChildren; i-- > 0;) {
      stack.emplace_back(node->mChildren[i], node_to_root);
    }
  }

  // Cameras and lights are named after the node that places them.
  auto placement = [&](const aiString& node_name) {
    const auto it = node_to_root_by_name.find(node_name.C_Str());
    return it == node_to_root_by_name.end() ? glm::mat4(1.0f) : it->second;
  };
  for (unsigned i = 0; i < scene->mNumCameras; ++i) {
    const aiCamera& cam = *scene->mCameras[i];
    if (auto c = convert_camera(cam, placement(cam.mName))) model.cameras.push_back(*c);
  }
  for (unsigned i = 0; i < scene->mNumLights; ++i) {
    const aiLight& light = *scene->mLights[i];
    if (auto l = convert_light(light, placement(light.mName))) model.lights.push_back(*l);
  }

  finish_loaded_model(model);
  return model;
}

}  // namespace farm
