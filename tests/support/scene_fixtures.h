#pragma once
// Small hand-built models and scenes for tests that must not depend on model files.
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <memory>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "renderer/scene/scene.h"

namespace farm::test {

// Quad a-b-c-d (counter-clockwise seen from the side its normal points to) as two triangles.
Model make_quad(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d);
// Axis-aligned box with flat, outward normals (24 vertices, 12 triangles).
Model make_box(glm::vec3 min, glm::vec3 max);
// n x n grid of quads on the z = 0 plane over [-1, 1]^2, vertices shared (a watertight surface).
Model make_grid(int n);
// UV sphere of radius 1 at the origin with smooth normals.
Model make_sphere(int rings, int segments);

// The matrix of an object translated, rotated `degrees` about `axis` and scaled (ObjectTransform).
glm::mat4 placed(glm::vec3 translate, glm::vec3 axis, float degrees, glm::vec3 scale);

SceneObject object_of(Model model, const glm::mat4& model_to_world = glm::mat4(1.0f),
                      const Material& material = Material{});

RenderSettings raster_settings(int width, int height, AovSet aovs = {});

// Renders the full frame as one tile through the engine contract.
TileBuffer render_full(const PreparedScene& scene, const RenderSettings& settings);

}  // namespace farm::test
