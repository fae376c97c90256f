#pragma once
// The largest image side anything here makes or reads: a 16384 x 16384 film of RGBA floats is
// already 4 GiB. The job file's render.width and render.height (job/job_limits.h) and the images
// a comparison reads (compare/image.cpp) are bounded by the same figure.

namespace farm {

inline constexpr int kMaxImageSide = 16384;

}  // namespace farm
