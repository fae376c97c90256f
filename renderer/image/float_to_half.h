#pragma once
// Floats to OpenEXR's half, as Imath::half(float) converts them (round to nearest, ties to even;
// overflow to infinity; denormals kept), for a frame's channels before they are written. Imath
// uses the F16C instructions only when the whole build targets them, which ours does not (it
// runs on any x86-64): converted one by one in software, the channels of a 640x480 frame took
// 2.3 ms, over half of writing its EXR. Here the F16C path is chosen at run time when the CPU has
// it, eight floats an instruction, and the software path otherwise; both give the same bits
// for every float but signalling NaNs (which the renderer never writes).
#include <cstddef>
#include <cstdint>

namespace farm {

// out[i] = the half bits of the float at first + i * stride bytes, for i < count.
void floats_to_halves(const char* first, std::size_t stride, std::size_t count, std::uint16_t* out);

}  // namespace farm
