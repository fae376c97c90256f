// Placeholder until the FLIP implementation lands (it is being written on its own branch): every
// call says so, and `farm compare --metric flip` fails with this message rather than a result.
#include "renderer/compare/flip.h"

#include <stdexcept>

namespace farm {

FlipResult flip_ldr(const Image&, const Image&, const FlipOptions&, ThreadPool*) {
  throw std::logic_error("FLIP is not implemented yet");
}
FlipResult flip_hdr(const Image&, const Image&, const FlipOptions&, ThreadPool*) {
  throw std::logic_error("FLIP is not implemented yet");
}
Image flip_magma(const Image& error_map) { return error_map; }

}  // namespace farm
