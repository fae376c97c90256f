// The dae loader (Assimp behind renderer/loaders/assimp_loader.cpp and its pre-checks): an input
// is one .dae file, loaded as a job's model is.
#include "tests/fuzz/model_fuzzing.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  farm::fuzz::load_model_bytes(farm::fuzz::as_bytes(data, size), ".dae");
  return 0;
}
