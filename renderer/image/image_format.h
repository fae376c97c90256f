#pragma once
// What kind of image a file holds, by its first bytes, never its name: the one sniff that the
// comparison's reader (compare/image.h) and the texture reader (texture/texture_file.h) share.
#include <cstdio>

namespace farm {

enum class ImageFormat { exr, png, jpeg, radiance, unknown };

// Looks at the first bytes of `in` and rewinds it.
ImageFormat sniff_image_format(std::FILE* in);

}  // namespace farm
