#pragma once
// What this CPU's vector units offer, asked once: the builds that pick code by the CPU at run time
// (the BVH traversal, geometry/traversal_isa.h; the preview encoder, image/preview.cpp) ask here.

namespace farm {

bool cpu_has_avx2();
// AVX-512 Foundation and Vector Length extensions.
bool cpu_has_avx512();

}  // namespace farm
