#include "server/cli/info_command.h"

#include <fmt/format.h>

#include <glm/vec3.hpp>
#include <memory>

#include "renderer/accel/prepared_scene.h"
#include "renderer/job/scene_builder.h"
#include "renderer/texture/environment_light.h"
#include "renderer/trace/emitter_facing.h"
#include "server/cli/job_file_options.h"

namespace farm {
namespace {

std::string vec(const glm::vec3& v) { return fmt::format("({:.4g}, {:.4g}, {:.4g})", v.x, v.y, v.z); }

void print_camera(const Camera& c) {
  fmt::print("  camera: position {} target {} up {} fov_y {:.4g} near {:.4g} far {:.4g}\n",
             vec(c.position), vec(c.target), vec(c.up), c.fov_y_degrees, c.near, c.far);
}

void print_light(const Light& l) {
  if (l.kind == Light::Kind::Directional) {
    fmt::print("  light: directional, direction {} intensity {}\n", vec(l.direction), vec(l.intensity));
  } else {
    fmt::print("  light: point, position {} intensity {}\n", vec(l.position), vec(l.intensity));
  }
}

// A lamp whose winding is reversed shines away from everything and leaves the image dark.
void warn_about_emitters_facing_away(Scene scene) {
  const PreparedScene prepared(std::move(scene));
  for (const EmitterFacingAway& e : find_emitters_facing_away(prepared)) {
    fmt::print("  warning: object '{}' material '{}': {} of {} emissive triangles shine away from "
               "the rest of the scene (only the front face shines: is the winding reversed? "
               "\"emission_sides\": \"both\" in the job's material makes both faces shine)\n",
               e.object, e.material, e.facing_away, e.checked);
  }
}

void print_model(const std::filesystem::path& file) {
  const auto shared = std::make_shared<const Model>(load_model(file));
  const Model& model = *shared;
  const AABB b = model.bounds();
  fmt::print("model {}\n", file.string());
  fmt::print("  {} triangles, {} vertices, {} mesh(es), {} material(s)\n", model.triangle_count(),
             model.vertex_count(), model.meshes.size(), model.materials.size());
  fmt::print("  bounds {} .. {}\n", vec(b.min), vec(b.max));
  for (const Mesh& m : model.meshes) {
    fmt::print("  mesh '{}': {} triangles, material '{}'\n", m.name, m.triangle_count(),
               model.materials[m.material].name);
  }
  for (const Material& m : model.materials) {
    fmt::print("  material '{}': ka {} kd {} ks {} ke {} shininess {:.4g} ior {:.4g} "
               "transmission {:.4g} emission_sides {}\n",
               m.name, vec(m.ambient), vec(m.diffuse), vec(m.specular), vec(m.emission),
               m.shininess, m.ior, m.transmission, to_string(m.emission_sides));
    if (const std::optional<MetalRoughness>& mr = m.metal_roughness) {
      fmt::print("    metal-roughness (the path tracer's): base colour {} metallic {:.4g} roughness {:.4g}\n",
                 vec(mr->base_colour), mr->metallic, mr->roughness);
    }
    if (m.alpha_mode == AlphaMode::Mask) {
      fmt::print("    alpha {:.4g} (times the base colour texture's), cut out below {:.4g}\n", m.alpha, m.alpha_cutoff);
    } else if (m.alpha_mode == AlphaMode::Blend) {
      fmt::print("    alpha {:.4g} (times the base colour texture's), blended\n", m.alpha);
    }
  }
  for (const Camera& c : model.cameras) print_camera(c);
  for (const Light& l : model.lights) print_light(l);
  // The model alone, in its own space.
  Scene scene;
  scene.objects.push_back(SceneObject{file.stem().string(), shared, glm::mat4(1.0f), model.materials});
  warn_about_emitters_facing_away(std::move(scene));
}

void print_job(const std::filesystem::path& file, const JobLoadOptions& load) {
  const Job job = load_job(file, load);
  const Scene scene = build_scene(job);
  const RenderSettings& r = job.render;
  fmt::print("job '{}' ({})\n", job.name, file.string());
  fmt::print("  {} object(s), {} triangles\n", scene.objects.size(), scene.triangle_count());
  for (const SceneObject& o : scene.objects) {
    fmt::print("  object '{}': {} triangles from {}\n", o.name, o.model->triangle_count(),
               o.model->source.string());
  }
  warn_about_emitters_facing_away(scene);
  print_camera(scene.camera);
  for (const Light& l : scene.lights) print_light(l);
  if (const auto& e = job.scene.environment) {
    const Texture* map = scene.environment->map();
    fmt::print("  environment: {} radiance {} intensity {} rotated {} degrees about +y\n",
               map ? fmt::format("map {} ({}x{})", e->map_as_written, map->width(), map->height()) : std::string("constant"),
               vec(e->radiance), e->intensity, e->rotate_degrees);
  } else {
    fmt::print("  ambient {} background {}\n", vec(scene.ambient), vec(scene.background));
  }
  fmt::print("  render: engine {} {}x{} spp {} max_depth {} seed {} tile_size {} threads {} "
             "accel {}\n",
             to_string(r.engine), r.width, r.height, r.spp, r.max_depth, r.seed, r.tile_size,
             r.threads, to_string(r.accel));
  std::string aovs;
  for (Aov a : kAllAovs) {
    if (r.aovs.has(a)) aovs += fmt::format("{}{}", aovs.empty() ? "" : " ", to_string(a));
  }
  fmt::print("  output: image {} preview {} aovs {}{}\n", job.output.image.string(),
             job.output.preview.empty() ? std::string("(none)") : job.output.preview.string(),
             aovs.empty() ? std::string("(none)") : aovs,
             job.output.video.empty() ? std::string() : " video " + job.output.video.string());
}

}  // namespace

void run_info_command(const std::filesystem::path& file, const JobLoadOptions& load) {
  if (file.extension() == ".json") {
    print_job(file, load);
  } else {
    print_model(file);
  }
}

void add_info_command(CLI::App& app, CommandTable& commands) {
  struct Options {
    std::filesystem::path file;
    JobLoadOptions load;
  };
  auto o = std::make_shared<Options>();
  CLI::App* info = app.add_subcommand("info", "Print a model's or a job's statistics");
  info->add_option("file", o->file, "Model (.dae .obj .ply .gltf .glb) or job (.json)")
      ->required()
      ->check(CLI::ExistingFile);
  add_asset_root_option(*info, o->load);
  commands.add(info, [o] {
    run_info_command(o->file, o->load);
    return 0;
  });
}

}  // namespace farm
