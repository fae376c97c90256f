// The glTF loader (tinygltf behind renderer/loaders/gltf_loader.cpp): an input is one file, loaded
// as a .glb when it starts with the binary container's magic and as a .gltf otherwise, so one
// corpus covers both forms.
#include "tests/fuzz/model_fuzzing.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes = farm::fuzz::as_bytes(data, size);
  farm::fuzz::load_model_bytes(bytes, bytes.substr(0, 4) == "glTF" ? ".glb" : ".gltf");
  return 0;
}
