#pragma once
// A height map (MTL's bump) turned into the tangent-space normal map it describes, so that it
// bends shading normals through the one normal-map path (docs/architecture.md, §8.4).
#include <memory>

#include "renderer/texture/texture.h"

namespace farm {

// The normal map of `height` (its luminance, linear, the height at each texel) scaled by `scale`
// (MTL's -bm): heights are measured in the texture's own uv units, so that a ramp from 0 to 1
// across the whole image rises by `scale` over a u span of 1, whatever its resolution. Slopes are
// central differences between neighbouring texels, wrapped or clamped at the edges as the
// sampler's modes say; each texel holds 0.5 + 0.5 n as a normal map's do (X along u, Y up the
// image, that is along -v, as glTF's normal maps).
std::shared_ptr<const Texture> normal_map_from_height(const Texture& height, float scale, TextureWrap wrap_u,
                                                      TextureWrap wrap_v);

}  // namespace farm
