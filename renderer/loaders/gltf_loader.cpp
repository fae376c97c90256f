// glTF 2.0 (.gltf, .glb) through tinygltf, one loader in one file (over 700 lines: the bounds
// checks below are most of it, and split apart they would be easier to leave out). Meshes are
// baked with their node's rest world transform; the node hierarchy and its animations are kept
// beside them (renderer/scene/model_animation.h) so that a frame can pose the baked meshes.
// Debian ships tinygltf as a shared library, so this file only includes the header (no
// TINYGLTF_IMPLEMENTATION; see renderer/CMakeLists.txt on link order).
// tinygltf parses the JSON and the buffers but leaves it to us to check that accessors fit their
// buffers, so every read below is bounds-checked: malformed input ends in an InputError, never in
// an out-of-bounds read.
#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/trigonometric.hpp>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "renderer/loaders/loaders.h"
#include "renderer/scene/model_animation.h"
#include "renderer/texture/material_textures.h"
#include "renderer/texture/texture_cache.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

// Animation keys in all channels of a file together: enough for minutes of dense motion capture on
// dozens of nodes, and a bound on the work a small malicious file can ask of every frame.
constexpr std::size_t kMaxAnimationKeys = 1'000'000;

// ---- File access: every file tinygltf reads is confined ----------------------------------------

// A .gltf could reach past the asset root with a buffer or image uri such as "../../secret",
// "/etc/passwd" or a FIFO. tinygltf reads the model and every file it names through these, and
// confine_loader_path decides; the first refusal is kept, so that the load fails naming it even
// where tinygltf carries on (an image it cannot read is only a warning to it).
struct GltfFiles {
  const ModelFile& model;
  std::string refusal;

  ConfinedFile confine(const std::string& path) {
    ConfinedFile c = confine_loader_path(model, path);
    if (c.refused() && refusal.empty()) refusal = c.reason;
    return c;
  }
};

// True unless nothing is there, so that a refused file fails in the read, with the reason.
bool file_exists(const std::string& path, void* user) {
  return static_cast<GltfFiles*>(user)->confine(path).verdict != Confinement::missing;
}

std::string no_expansion(const std::string& path, void*) { return path; }

bool confined_read(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                   void* user) {
  auto* files = static_cast<GltfFiles*>(user);
  const ConfinedFile c = files->confine(path);
  std::string why;
  if (c.allowed() && read_confined(c, *out, &why)) return true;
  if (c.allowed() && files->refusal.empty()) files->refusal = why;
  if (err) *err += (c.allowed() ? why : c.reason.empty() ? path + ": no such file" : c.reason) + "\n";
  return false;
}

bool refuse_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is not allowed";
  return false;
}

// tinygltf hands every image's bytes (a file's, a buffer view's, a data: URI's) to this loader,
// which keeps them as they are, encoded: the texture cache decodes an image only if a material
// uses it (material_textures), with its size checked before.
bool keep_encoded_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                        const unsigned char* bytes, int size, void*) {
  if (bytes != nullptr && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

// ---- Materials ----------------------------------------------------------------------------------

std::optional<float> extension_number(const tinygltf::ExtensionMap& extensions, const char* name,
                                      const char* key) {
  const auto it = extensions.find(name);
  if (it == extensions.end() || !it->second.IsObject() || !it->second.Has(key)) return std::nullopt;
  const tinygltf::Value& v = it->second.Get(key);
  if (!v.IsNumber()) return std::nullopt;
  return static_cast<float>(v.GetNumberAsDouble());
}

// The metal-roughness values, and their Phong counterpart (set_metal_roughness).
Material convert_material(const tinygltf::Material& in) {
  Material m;
  if (!in.name.empty()) m.name = in.name;
  m.ior = 1.5f;  // glTF's dielectrics, without KHR_materials_ior
  const tinygltf::PbrMetallicRoughness& pbr = in.pbrMetallicRoughness;
  glm::vec3 base(1.0f);
  if (pbr.baseColorFactor.size() >= 3) {
    base = glm::vec3(pbr.baseColorFactor[0], pbr.baseColorFactor[1], pbr.baseColorFactor[2]);
  }
  set_metal_roughness(m, base, glm::clamp(static_cast<float>(pbr.metallicFactor), 0.0f, 1.0f),
                      glm::clamp(static_cast<float>(pbr.roughnessFactor), 0.0f, 1.0f));

  // A double-sided glTF material is meant to be seen from both sides: its emission shines from
  // both too.
  if (pbr.baseColorFactor.size() >= 4) m.alpha = glm::clamp(static_cast<float>(pbr.baseColorFactor[3]), 0.0f, 1.0f);
  if (in.alphaMode == "MASK") m.alpha_mode = AlphaMode::Mask;
  if (in.alphaMode == "BLEND") m.alpha_mode = AlphaMode::Blend;
  m.alpha_cutoff = static_cast<float>(in.alphaCutoff);
  if (in.doubleSided) m.emission_sides = EmissionSides::Both;
  if (in.emissiveFactor.size() == 3) {
    m.emission = glm::vec3(in.emissiveFactor[0], in.emissiveFactor[1], in.emissiveFactor[2]);
  }
  if (auto strength =
          extension_number(in.extensions, "KHR_materials_emissive_strength", "emissiveStrength")) {
    m.emission *= *strength;
  }
  if (auto ior = extension_number(in.extensions, "KHR_materials_ior", "ior")) m.ior = *ior;
  if (auto transmission =
          extension_number(in.extensions, "KHR_materials_transmission", "transmissionFactor")) {
    m.transmission = glm::clamp(*transmission, 0.0f, 1.0f);
  }
  return m;
}

// ---- Reading one glTF document ------------------------------------------------------------------

struct AccessorView {
  const unsigned char* first = nullptr;  // start of element 0
  std::size_t stride = 0;
  std::size_t count = 0;
  int component_type = 0;

  const unsigned char* element(std::size_t i) const { return first + i * stride; }
};

class GltfReader {
 public:
  GltfReader(const ModelFile& source, const tinygltf::Model& gltf)
      : source_(source), file_(source.name), gltf_(gltf) {}

  Model read();

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(file_.string() + ": " + what);
  }

  AccessorView view(int index, int element_type, const std::string& what) const;
  std::vector<glm::vec3> read_vec3(int accessor, const std::string& what) const;
  std::vector<glm::vec2> read_texcoords(int accessor, const std::string& what) const;
  std::vector<glm::vec4> read_tangents(int accessor, const std::string& what) const;
  TextureSlot texture_slot(const tinygltf::TextureInfo& info, const std::string& material, const char* what,
                           TextureColourSpace space) const;
  std::shared_ptr<const MaterialTextures> material_textures(const tinygltf::Material& in) const;
  std::vector<float> read_times(int accessor, const std::string& what) const;
  std::vector<glm::quat> read_rotations(int accessor, const std::string& what) const;
  std::vector<std::uint32_t> read_indices(int accessor, std::size_t vertex_count,
                                          const std::string& what) const;
  std::vector<glm::uvec3> assemble_triangles(int mode, const std::vector<std::uint32_t>& idx,
                                             const std::string& what) const;

  ModelNode read_node(const tinygltf::Node& node, int index) const;
  void read_nodes();
  void read_animations();
  AnimationChannel read_channel(const tinygltf::Animation& animation,
                                const tinygltf::AnimationChannel& channel, const std::string& where,
                                std::size_t& keys) const;
  std::vector<int> root_nodes() const;
  void add_mesh(int mesh_index, int node, const glm::mat4& node_to_root);
  void add_camera(int camera_index, const glm::mat4& node_to_root);
  void add_light(const tinygltf::Node& node, const glm::mat4& node_to_root);
  std::uint32_t default_material();

  const ModelFile& source_;
  std::filesystem::path file_;
  const tinygltf::Model& gltf_;
  Model model_;
  std::optional<std::uint32_t> default_material_;
};

template <class T>
bool valid_index(int index, const std::vector<T>& items) {
  return index >= 0 && static_cast<std::size_t>(index) < items.size();
}

// A material's texture: the image its texture names (an external file, confined to the model's
// root and decoded through the process's cache), the texture's sampler and KHR_texture_transform.
// An empty slot when the material names none.
TextureSlot GltfReader::texture_slot(const tinygltf::TextureInfo& info, const std::string& material,
                                     const char* what, TextureColourSpace space) const {
  if (info.index < 0) return {};
  const std::string where = "material '" + material + "' " + what;
  if (!valid_index(info.index, gltf_.textures)) fail(where + ": no such texture " + std::to_string(info.index));
  // Meshes carry one set of texture coordinates: a map laid out on another would be read wrong.
  if (info.texCoord != 0) {
    fail(where + ": reads TEXCOORD_" + std::to_string(info.texCoord) + "; only TEXCOORD_0 is read");
  }
  const tinygltf::Texture& texture = gltf_.textures[static_cast<std::size_t>(info.index)];
  if (!valid_index(texture.source, gltf_.images)) fail(where + ": texture " + std::to_string(info.index) + " has no image");
  const tinygltf::Image& image = gltf_.images[static_cast<std::size_t>(texture.source)];
  // An image in the file itself (a .glb's buffer view, a data: URI) is decoded from its bytes;
  // one beside it is a file, confined to the root as the model is.
  const bool embedded = image.uri.empty() || image.uri.rfind("data:", 0) == 0;
  ConfinedFile file;
  if (!embedded) {
    file = confine_loader_path(source_, image.uri);
    if (!file.allowed()) fail(where + ": image '" + image.uri + "': " + (file.reason.empty() ? "no such file" : file.reason));
  } else if (image.image.empty()) {
    fail(where + ": image " + std::to_string(texture.source) + " has no data");
  }

  TextureSlot slot;
  if (texture.sampler >= 0) {
    if (!valid_index(texture.sampler, gltf_.samplers)) fail(where + ": no such sampler " + std::to_string(texture.sampler));
    const tinygltf::Sampler& sampler = gltf_.samplers[static_cast<std::size_t>(texture.sampler)];
    const auto wrap = [](int mode) {
      return mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE     ? TextureWrap::ClampToEdge
             : mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT ? TextureWrap::MirroredRepeat
                                                             : TextureWrap::Repeat;
    };
    slot.sampler.wrap_u = wrap(sampler.wrapS);
    slot.sampler.wrap_v = wrap(sampler.wrapT);
    if (sampler.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST) slot.sampler.magnify = TextureFilter::Nearest;
    switch (sampler.minFilter) {
      case TINYGLTF_TEXTURE_FILTER_NEAREST:
        slot.sampler.minify = TextureFilter::Nearest;
        slot.sampler.mipmaps = false;
        break;
      case TINYGLTF_TEXTURE_FILTER_LINEAR: slot.sampler.mipmaps = false; break;
      case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST:
      case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_LINEAR: slot.sampler.minify = TextureFilter::Nearest; break;
      default: break;  // linear with mipmaps, also when the file says nothing
    }
  }
  if (const auto it = info.extensions.find("KHR_texture_transform"); it != info.extensions.end() && it->second.IsObject()) {
    const tinygltf::Value& t = it->second;
    const auto pair = [&](const char* key, glm::vec2 fallback) {
      if (!t.Has(key)) return fallback;
      const tinygltf::Value& v = t.Get(key);
      if (!v.IsArray() || v.ArrayLen() != 2 || !v.Get(0).IsNumber() || !v.Get(1).IsNumber()) {
        fail(where + ": KHR_texture_transform's " + key + " is not two numbers");
      }
      return glm::vec2(static_cast<float>(v.Get(0).GetNumberAsDouble()), static_cast<float>(v.Get(1).GetNumberAsDouble()));
    };
    const float rotation = t.Has("rotation") && t.Get("rotation").IsNumber()
                               ? static_cast<float>(t.Get("rotation").GetNumberAsDouble())
                               : 0.0f;
    slot.transform = uv_transform(pair("offset", glm::vec2(0.0f)), rotation, pair("scale", glm::vec2(1.0f)));
    for (int c = 0; c < 3; ++c) {
      if (!all_finite(slot.transform[c])) fail(where + ": KHR_texture_transform is not finite");
    }
  }
  try {
    slot.texture = embedded ? TextureCache::process().get_embedded(source_.file.resolved, texture.source, image.image, space)
                            : TextureCache::process().get(file.resolved, space);
  } catch (const InputError& e) {
    fail(where + ": " + e.what());
  }
  return slot;
}

std::shared_ptr<const MaterialTextures> GltfReader::material_textures(const tinygltf::Material& in) const {
  const std::string name = in.name.empty() ? "(unnamed)" : in.name;
  const tinygltf::PbrMetallicRoughness& pbr = in.pbrMetallicRoughness;
  MaterialTextures textures;
  textures.base_colour = texture_slot(pbr.baseColorTexture, name, "baseColorTexture", TextureColourSpace::Srgb);
  // Data, not colour: blue is metalness, green roughness (glTF 2.0, 3.9.2).
  textures.metal_roughness =
      texture_slot(pbr.metallicRoughnessTexture, name, "metallicRoughnessTexture", TextureColourSpace::Linear);
  textures.emission = texture_slot(in.emissiveTexture, name, "emissiveTexture", TextureColourSpace::Srgb);
  // An occlusion map on a second set of texture coordinates (a baked lightmap's, often) is left
  // out rather than refused: it only darkens the rasterizer's and Whitted's ambient term.
  tinygltf::TextureInfo occlusion;
  occlusion.index = in.occlusionTexture.texCoord == 0 ? in.occlusionTexture.index : -1;
  occlusion.texCoord = in.occlusionTexture.texCoord;
  occlusion.extensions = in.occlusionTexture.extensions;
  textures.occlusion = texture_slot(occlusion, name, "occlusionTexture", TextureColourSpace::Linear);
  textures.occlusion_strength = glm::clamp(static_cast<float>(in.occlusionTexture.strength), 0.0f, 1.0f);
  tinygltf::TextureInfo normal;
  normal.index = in.normalTexture.index;
  normal.texCoord = in.normalTexture.texCoord;
  normal.extensions = in.normalTexture.extensions;
  textures.normal = texture_slot(normal, name, "normalTexture", TextureColourSpace::Linear);
  textures.normal_scale = static_cast<float>(in.normalTexture.scale);
  if (!std::isfinite(textures.normal_scale)) fail("material '" + name + "' normalTexture: scale is not finite");
  if (!textures.base_colour && !textures.metal_roughness && !textures.emission && !textures.occlusion &&
      !textures.normal) {
    return nullptr;
  }
  return std::make_shared<const MaterialTextures>(std::move(textures));
}

AccessorView GltfReader::view(int index, int element_type, const std::string& what) const {
  const std::string where = what + " (accessor " + std::to_string(index) + ")";
  if (!valid_index(index, gltf_.accessors)) fail(where + ": no such accessor");
  const tinygltf::Accessor& acc = gltf_.accessors[static_cast<std::size_t>(index)];
  if (acc.sparse.isSparse) fail(where + ": sparse accessors are not supported");
  if (acc.type != element_type) fail(where + ": unexpected element type");
  const int component_size =
      tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(acc.componentType));
  const int components = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(acc.type));
  if (component_size <= 0 || components <= 0) fail(where + ": invalid component type");
  const std::size_t element_size = static_cast<std::size_t>(component_size * components);

  AccessorView v;
  v.component_type = acc.componentType;
  v.stride = element_size;
  if (acc.count == 0) return v;

  if (!valid_index(acc.bufferView, gltf_.bufferViews)) fail(where + ": no such bufferView");
  const tinygltf::BufferView& bv = gltf_.bufferViews[static_cast<std::size_t>(acc.bufferView)];
  if (!valid_index(bv.buffer, gltf_.buffers)) fail(where + ": bufferView has no such buffer");
  const std::vector<unsigned char>& data = gltf_.buffers[static_cast<std::size_t>(bv.buffer)].data;
  // Every comparison is arranged so that no sum can overflow.
  if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset) {
    fail(where + ": bufferView runs past the end of its buffer");
  }
  if (bv.byteStride != 0) v.stride = bv.byteStride;
  if (v.stride < element_size) fail(where + ": byteStride is smaller than one element");
  if (acc.byteOffset > bv.byteLength || element_size > bv.byteLength - acc.byteOffset) {
    fail(where + ": accessor starts past the end of its bufferView");
  }
  const std::size_t room_after_first = bv.byteLength - acc.byteOffset - element_size;
  if (acc.count - 1 > room_after_first / v.stride) {
    fail(where + ": " + std::to_string(acc.count) + " elements do not fit in the bufferView");
  }
  v.first = data.data() + bv.byteOffset + acc.byteOffset;
  v.count = acc.count;
  return v;
}

std::vector<glm::vec3> GltfReader::read_vec3(int accessor, const std::string& what) const {
  const AccessorView v = view(accessor, TINYGLTF_TYPE_VEC3, what);
  if (v.count > 0 && v.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT) {
    fail(what + ": expected float components");
  }
  std::vector<glm::vec3> out(v.count);
  for (std::size_t i = 0; i < v.count; ++i) {
    float xyz[3];
    std::memcpy(xyz, v.element(i), sizeof xyz);  // buffers need not be aligned for float
    out[i] = glm::vec3(xyz[0], xyz[1], xyz[2]);
  }
  return out;
}

// Tangents: float VEC4, xyz a unit vector and w the bitangent's sign (glTF 2.0, 3.7.2.1). Values
// that are not finite are refused; a w other than -1 reads as +1.
std::vector<glm::vec4> GltfReader::read_tangents(int accessor, const std::string& what) const {
  const AccessorView v = view(accessor, TINYGLTF_TYPE_VEC4, what);
  if (v.count > 0 && v.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT) fail(what + ": expected float components");
  std::vector<glm::vec4> out(v.count);
  for (std::size_t i = 0; i < v.count; ++i) {
    float xyzw[4];
    std::memcpy(xyzw, v.element(i), sizeof xyzw);
    out[i] = glm::vec4(xyzw[0], xyzw[1], xyzw[2], xyzw[3] < 0.0f ? -1.0f : 1.0f);
    if (!all_finite(glm::vec3(out[i]))) fail(what + ": a tangent that is not finite");
  }
  return out;
}

// Texture coordinates: float, or normalized unsigned bytes or shorts (glTF 2.0, 3.7.2.1).
std::vector<glm::vec2> GltfReader::read_texcoords(int accessor, const std::string& what) const {
  const AccessorView v = view(accessor, TINYGLTF_TYPE_VEC2, what);
  const tinygltf::Accessor& acc = gltf_.accessors[static_cast<std::size_t>(accessor)];
  std::vector<glm::vec2> out(v.count);
  for (std::size_t i = 0; i < v.count; ++i) {
    const unsigned char* e = v.element(i);
    if (v.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT) {
      float uv[2];
      std::memcpy(uv, e, sizeof uv);
      out[i] = glm::vec2(uv[0], uv[1]);
    } else if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && acc.normalized) {
      out[i] = glm::vec2(e[0], e[1]) / 255.0f;
    } else if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT && acc.normalized) {
      std::uint16_t uv[2];
      std::memcpy(uv, e, sizeof uv);
      out[i] = glm::vec2(uv[0], uv[1]) / 65535.0f;
    } else {
      fail(what + ": texture coordinates must be float or normalized unsigned bytes or shorts");
    }
  }
  return out;
}

std::vector<float> GltfReader::read_times(int accessor, const std::string& what) const {
  const AccessorView v = view(accessor, TINYGLTF_TYPE_SCALAR, what);
  if (v.count > 0 && v.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT) {
    fail(what + ": key times must be float scalars");
  }
  std::vector<float> out(v.count);
  for (std::size_t i = 0; i < v.count; ++i) std::memcpy(&out[i], v.element(i), sizeof(float));
  return out;
}

// Rotation keys: float, or normalized integers scaled back to [-1, 1] as glTF 2.0 section 3.11
// gives them (a signed value's most negative code is clamped to -1).
std::vector<glm::quat> GltfReader::read_rotations(int accessor, const std::string& what) const {
  const AccessorView v = view(accessor, TINYGLTF_TYPE_VEC4, what);
  const tinygltf::Accessor& acc = gltf_.accessors[static_cast<std::size_t>(accessor)];
  const bool is_float = v.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT;
  if (v.count > 0 && !is_float && !acc.normalized) {
    fail(what + ": rotations must be float or normalized integer VEC4");
  }
  auto component = [&](const unsigned char* p, int c) -> float {
    switch (v.component_type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float f;
        std::memcpy(&f, p + 4 * c, sizeof f);
        return f;
      }
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const auto b = static_cast<signed char>(p[c]);
        return std::max(static_cast<float>(b) / 127.0f, -1.0f);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return static_cast<float>(p[c]) / 255.0f;
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        std::int16_t s;
        std::memcpy(&s, p + 2 * c, sizeof s);
        return std::max(static_cast<float>(s) / 32767.0f, -1.0f);
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t s;
        std::memcpy(&s, p + 2 * c, sizeof s);
        return static_cast<float>(s) / 65535.0f;
      }
      default: fail(what + ": rotations must be float, or normalized byte or short");
    }
  };
  std::vector<glm::quat> out;
  out.reserve(v.count);
  for (std::size_t i = 0; i < v.count; ++i) {
    const unsigned char* p = v.element(i);  // x, y, z, w; GLM's constructor takes w first
    out.emplace_back(component(p, 3), component(p, 0), component(p, 1), component(p, 2));
  }
  return out;
}

std::vector<std::uint32_t> GltfReader::read_indices(int accessor, std::size_t vertex_count,
                                                    const std::string& what) const {
  std::vector<std::uint32_t> out;
  if (accessor < 0) {  // non-indexed: vertices in order
    out.resize(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i) out[i] = static_cast<std::uint32_t>(i);
    return out;
  }
  const AccessorView v = view(accessor, TINYGLTF_TYPE_SCALAR, what + " indices");
  out.resize(v.count);
  for (std::size_t i = 0; i < v.count; ++i) {
    const unsigned char* p = v.element(i);
    switch (v.component_type) {
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: out[i] = *p; break;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t s;
        std::memcpy(&s, p, sizeof s);
        out[i] = s;
        break;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        std::memcpy(&out[i], p, sizeof(std::uint32_t));
        break;
      default: fail(what + ": indices must be unsigned byte, short or int");
    }
    if (out[i] >= vertex_count) {
      fail(what + ": index " + std::to_string(out[i]) + " is past the last of " +
           std::to_string(vertex_count) + " vertices");
    }
  }
  return out;
}

std::vector<glm::uvec3> GltfReader::assemble_triangles(int mode,
                                                       const std::vector<std::uint32_t>& idx,
                                                       const std::string& what) const {
  std::vector<glm::uvec3> tris;
  const std::size_t n = idx.size();
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    if (n % 3 != 0) fail(what + ": " + std::to_string(n) + " indices do not make whole triangles");
    for (std::size_t i = 0; i < n; i += 3) tris.emplace_back(idx[i], idx[i + 1], idx[i + 2]);
    return tris;
  }
  // Strips and fans repeat indices to stitch pieces together; those triangles have no area.
  auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    if (a != b && b != c && a != c) tris.emplace_back(a, b, c);
  };
  for (std::size_t i = 0; i + 2 < n; ++i) {
    if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      // Every second triangle of a strip is flipped back to keep one winding (glTF 2.0, 3.7.2.1).
      if (i % 2 == 0) add(idx[i], idx[i + 1], idx[i + 2]);
      else add(idx[i], idx[i + 2], idx[i + 1]);
    } else {
      add(idx[i + 1], idx[i + 2], idx[0]);
    }
  }
  return tris;
}

std::uint32_t GltfReader::default_material() {
  // glTF's own default (white, fully metallic, rough) would turn black under our Phong mapping, so
  // primitives without a material get ours.
  if (!default_material_) {
    default_material_ = static_cast<std::uint32_t>(model_.materials.size());
    model_.materials.emplace_back();
  }
  return *default_material_;
}

void GltfReader::add_mesh(int mesh_index, int node, const glm::mat4& node_to_root) {
  if (!valid_index(mesh_index, gltf_.meshes)) {
    fail("node refers to missing mesh " + std::to_string(mesh_index));
  }
  const tinygltf::Mesh& in = gltf_.meshes[static_cast<std::size_t>(mesh_index)];
  for (std::size_t p = 0; p < in.primitives.size(); ++p) {
    const tinygltf::Primitive& prim = in.primitives[p];
    const std::string what =
        "mesh " + std::to_string(mesh_index) + " primitive " + std::to_string(p);
    const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
    if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE ||
        mode == TINYGLTF_MODE_LINE_LOOP || mode == TINYGLTF_MODE_LINE_STRIP) {
      continue;  // no surface to render
    }
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        mode != TINYGLTF_MODE_TRIANGLE_FAN) {
      fail(what + ": unknown primitive mode " + std::to_string(mode));
    }
    const auto position = prim.attributes.find("POSITION");
    if (position == prim.attributes.end()) continue;  // the spec says to skip such primitives

    Mesh mesh;
    mesh.node = node;
    mesh.name = in.name.empty() ? "mesh " + std::to_string(mesh_index) : in.name;
    if (in.primitives.size() > 1) mesh.name += "/" + std::to_string(p);
    mesh.positions = read_vec3(position->second, what + " POSITION");
    if (const auto normal = prim.attributes.find("NORMAL"); normal != prim.attributes.end()) {
      mesh.normals = read_vec3(normal->second, what + " NORMAL");
      if (mesh.normals.size() != mesh.positions.size()) {
        fail(what + ": NORMAL and POSITION counts differ");
      }
    }
    if (const auto tangent = prim.attributes.find("TANGENT"); tangent != prim.attributes.end()) {
      mesh.tangents = read_tangents(tangent->second, what + " TANGENT");
      if (mesh.tangents.size() != mesh.positions.size()) fail(what + ": TANGENT and POSITION counts differ");
    }
    if (const auto uv = prim.attributes.find("TEXCOORD_0"); uv != prim.attributes.end()) {
      mesh.uvs = read_texcoords(uv->second, what + " TEXCOORD_0");
      if (mesh.uvs.size() != mesh.positions.size()) fail(what + ": TEXCOORD_0 and POSITION counts differ");
    }
    const std::vector<std::uint32_t> indices =
        read_indices(prim.indices, mesh.positions.size(), what);
    mesh.triangles = assemble_triangles(mode, indices, what);

    if (prim.material < 0) {
      mesh.material = default_material();
    } else if (valid_index(prim.material, gltf_.materials)) {
      mesh.material = static_cast<std::uint32_t>(prim.material);  // file materials come first
    } else {
      fail(what + ": no such material " + std::to_string(prim.material));
    }
    bake_node_transform(mesh, node_to_root);
    model_.meshes.push_back(std::move(mesh));
  }
}

void GltfReader::add_camera(int camera_index, const glm::mat4& node_to_root) {
  if (!valid_index(camera_index, gltf_.cameras)) {
    fail("node refers to missing camera " + std::to_string(camera_index));
  }
  const tinygltf::Camera& in = gltf_.cameras[static_cast<std::size_t>(camera_index)];
  if (in.type != "perspective") return;  // our cameras are pinholes only
  const tinygltf::PerspectiveCamera& p = in.perspective;
  const std::string what = "camera " + std::to_string(camera_index);
  if (!(p.yfov > 0.0 && p.yfov < glm::pi<double>())) fail(what + ": yfov must be in (0, pi)");
  if (!(p.znear > 0.0) || !std::isfinite(p.znear)) fail(what + ": znear must be positive");

  Camera cam;
  cam.fov_y_degrees = static_cast<float>(glm::degrees(p.yfov));
  cam.near = static_cast<float>(p.znear);
  // No zfar means an infinite projection in glTF; our cameras need a finite far plane.
  cam.far = p.zfar > 0.0 ? static_cast<float>(p.zfar) : 1000.0f;
  if (!(cam.far > cam.near) || !std::isfinite(cam.far)) fail(what + ": zfar must exceed znear");
  if (p.aspectRatio > 0.0 && std::isfinite(p.aspectRatio)) {
    cam.aspect = static_cast<float>(p.aspectRatio);
  }

  // A glTF camera looks down its node's -Z with +Y up.
  const glm::mat3 linear(node_to_root);
  const glm::vec3 forward = linear * glm::vec3(0.0f, 0.0f, -1.0f);
  const glm::vec3 up = linear * glm::vec3(0.0f, 1.0f, 0.0f);
  if (!(glm::length(forward) > 0.0f) || !(glm::length(up) > 0.0f)) {
    fail(what + ": its node has a singular transform");
  }
  cam.position = glm::vec3(node_to_root[3]);
  cam.target = cam.position + glm::normalize(forward);
  cam.up = glm::normalize(up);
  if (!all_finite(cam.position) || !all_finite(cam.target) || !all_finite(cam.up)) {
    fail(what + ": its placement is not finite");
  }
  model_.cameras.push_back(cam);
}

// KHR_lights_punctual: tinygltf 2.7 parses the lights into Model::lights, but a node's reference
// stays in node.extensions["KHR_lights_punctual"]["light"].
void GltfReader::add_light(const tinygltf::Node& node, const glm::mat4& node_to_root) {
  const auto ext = node.extensions.find("KHR_lights_punctual");
  if (ext == node.extensions.end() || !ext->second.IsObject() || !ext->second.Has("light")) return;
  const tinygltf::Value& ref = ext->second.Get("light");
  if (!ref.IsInt()) fail("a node's KHR_lights_punctual light is not an index");
  const int index = ref.GetNumberAsInt();
  if (!valid_index(index, gltf_.lights)) {
    fail("node refers to missing light " + std::to_string(index));
  }
  const tinygltf::Light& in = gltf_.lights[static_cast<std::size_t>(index)];
  const std::string what = "light " + std::to_string(index);

  glm::vec3 colour(1.0f);
  if (in.color.size() == 3) colour = glm::vec3(in.color[0], in.color[1], in.color[2]);
  // glTF gives point and spot intensity in candela, i.e. irradiance I / r^2 at distance r, which is
  // what our point lights mean; directional intensity is lux, our directional irradiance.
  Light light;
  light.intensity = colour * static_cast<float>(in.intensity);
  if (!all_finite(light.intensity)) fail(what + ": intensity is not finite");
  if (in.type == "point" || in.type == "spot") {  // spot: no cone in our model
    light.kind = Light::Kind::Point;
    light.position = glm::vec3(node_to_root[3]);
    if (!all_finite(light.position)) fail(what + ": its placement is not finite");
  } else if (in.type == "directional") {
    const glm::vec3 d = glm::mat3(node_to_root) * glm::vec3(0.0f, 0.0f, -1.0f);
    if (!(glm::length(d) > 0.0f) || !all_finite(d)) {
      fail(what + ": its node has a singular transform");
    }
    light.kind = Light::Kind::Directional;
    light.direction = glm::normalize(d);
  } else {
    fail(what + ": unknown light type '" + in.type + "'");
  }
  model_.lights.push_back(light);
}

ModelNode GltfReader::read_node(const tinygltf::Node& node, int index) const {
  const std::string what = "node " + std::to_string(index);
  auto number = [&](const std::vector<double>& values, std::size_t i) {
    const float v = static_cast<float>(values[i]);
    if (!std::isfinite(v)) fail(what + ": transform is not finite");
    return v;
  };
  auto vec3 = [&](const std::vector<double>& v) {
    return glm::vec3(number(v, 0), number(v, 1), number(v, 2));
  };
  ModelNode out;
  out.name = node.name;
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16) fail(what + ": matrix must have 16 numbers");
    glm::mat4 m;
    // glTF matrices are column-major, like GLM's.
    for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = number(node.matrix, static_cast<std::size_t>(i));
    out.matrix = m;
    return out;
  }
  if (!node.translation.empty()) {
    if (node.translation.size() != 3) fail(what + ": translation must have 3 numbers");
    out.translation = vec3(node.translation);
  }
  if (!node.rotation.empty()) {
    if (node.rotation.size() != 4) fail(what + ": rotation must have 4 numbers");
    const std::vector<double>& r = node.rotation;  // x, y, z, w; GLM's constructor takes w first
    const glm::quat q(number(r, 3), number(r, 0), number(r, 1), number(r, 2));
    if (!(glm::length(q) > 0.0f)) fail(what + ": rotation is not a unit quaternion");
    out.rotation = glm::normalize(q);
  }
  if (!node.scale.empty()) {
    if (node.scale.size() != 3) fail(what + ": scale must have 3 numbers");
    out.scale = vec3(node.scale);
  }
  return out;
}

// Every node of the file, not only those of the scene shown, so that animation channels index
// them as the file does. glTF requires the nodes to form disjoint trees: each node has at most one
// parent, and (checked by node_world_matrices) no node is its own ancestor.
void GltfReader::read_nodes() {
  model_.nodes.reserve(gltf_.nodes.size());
  for (std::size_t i = 0; i < gltf_.nodes.size(); ++i) {
    model_.nodes.push_back(read_node(gltf_.nodes[i], static_cast<int>(i)));
  }
  for (std::size_t i = 0; i < gltf_.nodes.size(); ++i) {
    for (const int c : gltf_.nodes[i].children) {
      if (!valid_index(c, gltf_.nodes)) {
        fail("node " + std::to_string(i) + " refers to missing child node " + std::to_string(c));
      }
      ModelNode& child = model_.nodes[static_cast<std::size_t>(c)];
      if (child.parent >= 0) {
        fail("node " + std::to_string(c) +
             " appears twice in the node hierarchy (a child of node " +
             std::to_string(child.parent) + " and of node " + std::to_string(i) + ")");
      }
      child.parent = static_cast<int>(i);
    }
  }
}

AnimationChannel GltfReader::read_channel(const tinygltf::Animation& animation,
                                          const tinygltf::AnimationChannel& in,
                                          const std::string& where, std::size_t& keys) const {
  AnimationChannel out;
  if (in.target_path == "translation") out.path = AnimationPath::Translation;
  else if (in.target_path == "rotation") out.path = AnimationPath::Rotation;
  else if (in.target_path == "scale") out.path = AnimationPath::Scale;
  else fail(where + ": unknown target path '" + in.target_path + "'");

  if (!valid_index(in.target_node, gltf_.nodes)) {
    fail(where + ": targets missing node " + std::to_string(in.target_node));
  }
  out.node = in.target_node;
  const ModelNode& node = model_.nodes[static_cast<std::size_t>(in.target_node)];
  if (node.matrix) {
    fail(where + ": targets node " + std::to_string(in.target_node) +
         (node.name.empty() ? "" : " '" + node.name + "'") +
         ", which has a matrix (glTF allows animating only nodes given as translation, rotation "
         "and scale)");
  }

  if (!valid_index(in.sampler, animation.samplers)) {
    fail(where + ": no such sampler " + std::to_string(in.sampler));
  }
  const tinygltf::AnimationSampler& sampler =
      animation.samplers[static_cast<std::size_t>(in.sampler)];
  SamplerInterpolation& interpolation = out.sampler.interpolation;
  if (sampler.interpolation == "LINEAR") interpolation = SamplerInterpolation::Linear;
  else if (sampler.interpolation == "STEP") interpolation = SamplerInterpolation::Step;
  else if (sampler.interpolation == "CUBICSPLINE") interpolation = SamplerInterpolation::CubicSpline;
  else fail(where + ": unknown interpolation '" + sampler.interpolation + "'");

  // The key count is known once the accessor is checked, before anything is read.
  const AccessorView times = view(sampler.input, TINYGLTF_TYPE_SCALAR, where + " sampler input");
  keys += times.count;
  if (keys > kMaxAnimationKeys) {
    fail(where + ": the animations have more than " + std::to_string(kMaxAnimationKeys) +
         " keys in all");
  }
  out.sampler.times = read_times(sampler.input, where + " sampler input");
  const std::string output = where + " sampler output";
  if (out.path == AnimationPath::Rotation) {
    out.sampler.quat_values = read_rotations(sampler.output, output);
  } else {
    out.sampler.vec3_values = read_vec3(sampler.output, output);
  }
  if (const std::string problem = sampler_problem(out.sampler, out.path); !problem.empty()) {
    fail(where + ": " + problem);
  }
  // Keyed rotations are unit quaternions to the file's rounding; make them unit to ours. (A
  // spline's tangents are no rotations, and its result is normalised when it is sampled.)
  if (out.sampler.interpolation != SamplerInterpolation::CubicSpline) {
    for (glm::quat& q : out.sampler.quat_values) q = glm::normalize(q);
  }
  return out;
}

void GltfReader::read_animations() {
  std::size_t keys = 0;
  for (std::size_t a = 0; a < gltf_.animations.size(); ++a) {
    const tinygltf::Animation& in = gltf_.animations[a];
    ModelAnimation animation;
    animation.name = in.name;
    const std::string name =
        "animation " + std::to_string(a) + (in.name.empty() ? "" : " '" + in.name + "'");
    std::set<std::pair<int, AnimationPath>> targets;
    for (std::size_t c = 0; c < in.channels.size(); ++c) {
      const tinygltf::AnimationChannel& channel = in.channels[c];
      // Morph target weights: our meshes have none to blend. A channel without a target is
      // skipped too (tinygltf itself drops one whose target has no node, which glTF leaves to
      // extensions; the channel numbers below count only the channels tinygltf kept).
      const bool no_target = channel.target_node == -1 && channel.target_path.empty();
      if (channel.target_path == "weights" || no_target) continue;
      const std::string where = name + " channel " + std::to_string(c);
      AnimationChannel out = read_channel(in, channel, where, keys);
      if (!targets.emplace(out.node, out.path).second) {
        fail(where + ": node " + std::to_string(out.node) + "'s " + channel.target_path +
             " is animated by an earlier channel too (glTF allows one per target)");
      }
      animation.channels.push_back(std::move(out));
    }
    model_.animations.push_back(std::move(animation));
  }
}

std::vector<int> GltfReader::root_nodes() const {
  if (!gltf_.scenes.empty()) {
    const int scene = gltf_.defaultScene < 0 ? 0 : gltf_.defaultScene;
    if (!valid_index(scene, gltf_.scenes)) {
      fail("default scene " + std::to_string(scene) + " does not exist");
    }
    return gltf_.scenes[static_cast<std::size_t>(scene)].nodes;
  }
  // No scene at all: take every node that is nobody's child.
  std::vector<bool> is_child(gltf_.nodes.size(), false);
  for (const tinygltf::Node& n : gltf_.nodes)
    for (int c : n.children)
      if (valid_index(c, gltf_.nodes)) is_child[static_cast<std::size_t>(c)] = true;
  std::vector<int> roots;
  for (std::size_t i = 0; i < gltf_.nodes.size(); ++i)
    if (!is_child[i]) roots.push_back(static_cast<int>(i));
  return roots;
}

Model GltfReader::read() {
  model_.source = file_;
  for (const tinygltf::Material& in : gltf_.materials) {
    Material m = convert_material(in);
    m.textures = material_textures(in);
    if (!all_finite(m.diffuse) || !all_finite(m.specular) || !all_finite(m.emission) ||
        !std::isfinite(m.ior) || !std::isfinite(m.alpha_cutoff)) {
      fail("material '" + m.name + "' has values that are not finite");
    }
    model_.materials.push_back(m);
  }

  read_nodes();
  read_animations();
  std::vector<glm::mat4> rest_world;  // what every mesh is baked with
  try {
    rest_world = node_world_matrices(model_, nullptr, 0.0);
  } catch (const InputError& e) {  // a cycle
    fail(e.what());
  }
  std::vector<bool> animated(gltf_.nodes.size(), false);
  for (const ModelAnimation& a : model_.animations)
    for (const AnimationChannel& c : a.channels) animated[static_cast<std::size_t>(c.node)] = true;

  // Depth-first walk of the scene shown, with an explicit stack, carrying whether an animation
  // moves the node or an ancestor. read_nodes has made the hierarchy a forest, so a node met twice
  // is a root listed twice or listed though it has a parent.
  std::vector<bool> visited(gltf_.nodes.size(), false);
  std::vector<std::pair<int, bool>> stack;
  const std::vector<int> roots = root_nodes();
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) {
    if (!valid_index(*it, gltf_.nodes)) fail("no such node " + std::to_string(*it));
    if (const int parent = model_.nodes[static_cast<std::size_t>(*it)].parent; parent >= 0) {
      fail("node " + std::to_string(*it) +
           " is listed as a root of the scene but is a child of node " + std::to_string(parent));
    }
    stack.emplace_back(*it, false);
  }
  while (!stack.empty()) {
    const auto [index, parent_moves] = stack.back();
    stack.pop_back();
    const std::size_t i = static_cast<std::size_t>(index);
    if (visited[i]) fail("node " + std::to_string(index) + " appears twice in the node hierarchy");
    visited[i] = true;
    const tinygltf::Node& node = gltf_.nodes[i];
    const glm::mat4& node_to_root = rest_world[i];
    const bool moves = parent_moves || animated[i];
    if (node.mesh >= 0) {
      // Posing undoes the rest transform the mesh is baked with (rest_to_posed_matrices).
      if (moves && !invertible_for_posing(node_to_root)) {
        fail("node " + std::to_string(index) +
             (model_.nodes[i].name.empty() ? "" : " '" + model_.nodes[i].name + "'") +
             " is animated, or under an animated node, but its rest transform is singular or "
             "nearly so: its mesh baked with it could not be posed");
      }
      add_mesh(node.mesh, index, node_to_root);
    }
    if (node.camera >= 0) add_camera(node.camera, node_to_root);
    add_light(node, node_to_root);
    for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) {
      stack.emplace_back(*c, moves);
    }
  }

  finish_loaded_model(model_);
  return std::move(model_);
}

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

}  // namespace

Model load_gltf(const ModelFile& file) {
  const std::string name = file.name.string();
  GltfFiles files{file, {}};

  tinygltf::TinyGLTF loader;
  // Set by name: tinygltf 2.8 (Ubuntu 24.04) added GetFileSizeInBytes before user_data; left
  // null, it is not called.
  tinygltf::FsCallbacks callbacks{};
  callbacks.FileExists = &file_exists;
  callbacks.ExpandFilePath = &no_expansion;
  callbacks.ReadWholeFile = &confined_read;
  callbacks.WriteWholeFile = &refuse_write;
  callbacks.user_data = &files;
  loader.SetFsCallbacks(callbacks);
  loader.SetImageLoader(&keep_encoded_image, nullptr);

  tinygltf::Model gltf;
  std::string err, warn;
  bool ok = false;
  try {
    std::string ext = file.name.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool binary = ext == ".glb";
    const std::string path = file.file.resolved.string();
    ok = binary ? loader.LoadBinaryFromFile(&gltf, &err, &warn, path)
                : loader.LoadASCIIFromFile(&gltf, &err, &warn, path);
  } catch (const std::exception& e) {  // allocation failures on absurd sizes
    throw InputError(name + ": " + e.what());
  }
  if (!files.refusal.empty()) throw InputError(name + ": " + files.refusal);
  if (!ok) {
    std::string message = name + ": " + (err.empty() ? "not a valid glTF file" : trimmed(err));
    if (!warn.empty()) message += " (" + trimmed(warn) + ")";
    throw InputError(message);
  }
  // Warnings alone do not stop the load: the textures a material uses are read by the reader,
  // which fails on one it cannot read.
  return GltfReader(file, gltf).read();
}

}  // namespace farm
