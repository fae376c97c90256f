#pragma once
// Emitters that shine away from the scene: a likely winding mistake. An emissive triangle shines
// from its front face only (Material::emission_sides), so a lamp modelled with its winding
// reversed lights almost nothing and the image goes dark; `farm info` warns about it.
#include <cstddef>
#include <string>
#include <vector>

namespace farm {

class PreparedScene;

struct EmitterFacingAway {
  std::string object;           // SceneObject::name
  std::string material;         // Material::name
  std::size_t facing_away = 0;  // emissive triangles (of those checked) that face away
  std::size_t checked = 0;      // emissive triangles checked: all, or an even sample of many
};

// The front-only emissive triangles of one object and material make a group. From points on
// them, rays go out over both hemispheres (cosine-weighted, a fixed pattern) and meet the scene;
// a ray that meets nothing counts as travelling the scene's diagonal.
//  - An open group (a panel; its area-weighted normals do not cancel) is judged triangle by
//    triangle, by what lies around it (rays that meet the group itself are left out): a triangle
//    faces away when its front meets nothing while its back meets something (a lamp shining into
//    the void with the scene behind it), or when its front is much more hemmed in than its back,
//    the mean distance in front under a quarter of the mean behind (a lamp just under a ceiling
//    shining into the ceiling, with the room behind it).
//  - A closed group (its normals cancel, as a glowing ball's) has its own inside behind it, so it
//    is judged as a whole: it faces away when its front is the more hemmed-in side, its normals
//    pointing inwards. Alone in a scene (one side meets nothing) it is never reported: a glowing
//    ball and a dome around the camera are both fine.
// Groups with triangles that face away are returned in scene order.
std::vector<EmitterFacingAway> find_emitters_facing_away(const PreparedScene& scene);

}  // namespace farm
