#include "server/bench/rt_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <numbers>
#include <optional>
#include <string>
#include <stdexcept>
#include <thread>
#include <functional>
#include <memory>
#include <vector>

#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"
#include "renderer/geometry/traversal_isa.h"
#include "renderer/trace/sampler.h"
#include "renderer/util/input_error.h"
#include "server/bench/bench_scenes.h"
#include "server/bench/bench_support.h"
#include "server/bench/embree_direct.h"

namespace farm {
namespace {

using Clock = std::chrono::steady_clock;
using bench::seconds_since;

// Coherent rays: a square grid of camera rays that frames the whole scene.
std::vector<Ray> primary_rays(const AABB& bounds, std::uint64_t count) {
  const int side = static_cast<int>(std::sqrt(static_cast<double>(count)));
  Camera camera;
  const glm::vec3 centre = bounds.center();
  const float radius = 0.5f * glm::length(bounds.extent());
  camera.target = centre;
  camera.position = centre + glm::normalize(glm::vec3(0.6f, 0.5f, 1.0f)) * (radius / std::tan(glm::radians(20.0f)));
  std::vector<Ray> rays;
  rays.reserve(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      rays.push_back(camera.primary_ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f, side, side));
  return rays;
}

// Incoherent rays: origins uniform in the bounds, directions uniform on the sphere.
std::vector<Ray> incoherent_rays(const AABB& bounds, std::uint64_t count) {
  std::vector<Ray> rays(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    const SampleKey key{7, i, 0};
    const glm::vec3 u{sample_uniform(key, 0), sample_uniform(key, 1), sample_uniform(key, 2)};
    const float z = 1.0f - 2.0f * sample_uniform(key, 3);
    const float phi = 2.0f * std::numbers::pi_v<float> * sample_uniform(key, 4);
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    rays[i].origin = bounds.min + u * bounds.extent();
    rays[i].direction = {r * std::cos(phi), r * std::sin(phi), z};
  }
  return rays;
}

struct RayRates {
  double closest = 0.0, any = 0.0;  // Mrays/s over all threads
  double packet = 0.0, packet_any = 0.0;  // closest and any hit, the rays in packets of 8 in a row (primary rays only)
  std::uint64_t closest_hits = 0;    // rays with a closest hit: the structures must agree on them
  std::uint64_t any_hits = 0;        // rays blocked
  std::uint64_t packet_hits = 0, packet_any_hits = 0;  // the same, asked in packets
};

// A closest-hit or any-hit query of up to 8 consecutive rays (`lanes`): the lanes hit.
using PacketQuery = std::function<unsigned(const Ray*, unsigned)>;
struct PacketQueries {
  PacketQuery closest, any;
};

// Each query of `rays` timed on `threads` threads, each its contiguous share (std::thread: the
// bench measures the structure, not the farm's pool).
// With `packets`, the closest and any hit are also timed a packet of 8 rays at a time (each
// thread's share starts at a multiple of 8, so the packets are the same whatever the thread count).
RayRates measure(const std::vector<Ray>& rays, int threads, const std::function<bool(const Ray&)>& closest,
                 const std::function<bool(const Ray&)>& any, const PacketQueries* in_eights = nullptr) {
  std::uint64_t hits = 0;
  const auto run = [&](const std::function<std::uint64_t(std::size_t, std::size_t)>& span) {
    std::vector<std::uint64_t> counts(static_cast<std::size_t>(threads), 0);
    const Clock::time_point t = Clock::now();
    std::vector<std::thread> pool;
    for (int k = 0; k < threads; ++k) {
      pool.emplace_back([&, k] {
        const std::size_t packets = (rays.size() + 7) / 8, share = static_cast<std::size_t>(threads);
        const std::size_t begin = 8 * (packets * static_cast<std::size_t>(k) / share);
        const std::size_t end = std::min(rays.size(), 8 * (packets * static_cast<std::size_t>(k + 1) / share));
        counts[static_cast<std::size_t>(k)] = span(begin, end);
      });
    }
    for (std::thread& thread : pool) thread.join();
    const double mrays = static_cast<double>(rays.size()) / seconds_since(t) / 1e6;
    hits = 0;
    for (std::uint64_t c : counts) hits += c;
    return mrays;
  };
  const auto one_by_one = [&](const std::function<bool(const Ray&)>& query) {
    return [&](std::size_t begin, std::size_t end) {
      std::uint64_t c = 0;
      for (std::size_t i = begin; i < end; ++i) c += query(rays[i]) ? 1 : 0;
      return c;
    };
  };
  RayRates r;
  r.closest = run(one_by_one(closest));
  r.closest_hits = hits;
  r.any = run(one_by_one(any));
  r.any_hits = hits;
  const auto in_packets = [&](const PacketQuery& query) {
    return [&](std::size_t begin, std::size_t end) {
      std::uint64_t c = 0;
      for (std::size_t i = begin; i < end; i += 8) {
        const std::size_t n = std::min<std::size_t>(8, end - i);
        c += static_cast<std::uint64_t>(std::popcount(query(&rays[i], (1u << n) - 1u)));
      }
      return c;
    };
  };
  if (in_eights) {
    r.packet = run(in_packets(in_eights->closest));
    r.packet_hits = hits;
    r.packet_any = run(in_packets(in_eights->any));
    r.packet_any_hits = hits;
  }
  return r;
}

// One structure under test: its queries, built once and timed at every thread count.
struct Subject {
  std::string name;
  double build_ms = 0.0;
  std::uint64_t rays = 0;
  std::function<bool(const Ray&)> closest, any;
  PacketQueries packets;
  std::shared_ptr<void> keep;  // what the queries use
  std::optional<TraversalIsa> isa;  // our BVH's traversal forced to this build; none: the CPU's
};

void bench_scene(const std::string& name, Scene scene, const RtBenchOptions& o, bool with_naive) {
  const PreparedScene prepared(std::move(scene));
  const AABB bounds = prepared.world_bounds();
  std::vector<AccelKind> accels{AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Embree};
  if (with_naive) accels.push_back(AccelKind::Naive);
  std::vector<Subject> subjects, extra_rows;
  for (AccelKind accel : accels) {
    Subject s;
    s.name = to_string(accel);
    s.rays = accel == AccelKind::Naive ? o.naive_rays : o.rays;
    const Clock::time_point t = Clock::now();
    std::shared_ptr<SceneIntersector> intersector = build_scene_intersector(prepared, accel);
    s.build_ms = seconds_since(t) * 1e3;
    s.closest = [intersector](const Ray& ray) {
      SurfaceHit hit;
      return intersector->find_closest(ray, hit);  // the hit alone, as embree-direct finds it
    };
    s.any = [intersector](const Ray& ray) { return intersector->occluded(ray); };
    s.packets.closest = [intersector](const Ray* rays, unsigned lanes) {
      std::array<SurfaceHit, 8> hits;
      return intersector->find_closest_packet(rays, lanes, hits.data());
    };
    s.packets.any = [intersector](const Ray* rays, unsigned lanes) { return intersector->occluded_packet(rays, lanes); };
    subjects.push_back(s);
    if (accel == AccelKind::Bvh) {
      // The same tree walked by each lesser build this CPU runs (the x86-64 baseline, AVX2 under
      // AVX-512), to show what the wider instruction sets buy.
      for (TraversalIsa isa : {TraversalIsa::Avx2, TraversalIsa::Sse}) {
        if (isa >= best_traversal_isa()) continue;
        Subject lesser = s;
        lesser.name = fmt::format("bvh-{}", to_string(isa));
        lesser.isa = isa;
        extra_rows.push_back(std::move(lesser));
      }
    }
  }
  subjects.insert(subjects.end(), extra_rows.begin(), extra_rows.end());
  {
    // The anchor: Embree as its users call it (embree_direct.h).
    Subject s;
    s.name = "embree-direct";
    s.rays = o.rays;
    const Clock::time_point t = Clock::now();
    auto direct = std::make_shared<const EmbreeDirect>(prepared);
    s.build_ms = seconds_since(t) * 1e3;
    s.closest = [direct](const Ray& ray) { return direct->closest_hit(ray); };
    s.any = [direct](const Ray& ray) { return direct->occluded(ray); };
    s.packets.closest = [direct](const Ray* rays, unsigned lanes) { return direct->closest_hit8(rays, lanes); };
    s.packets.any = [direct](const Ray* rays, unsigned lanes) { return direct->occluded8(rays, lanes); };
    subjects.push_back(std::move(s));
  }
  const std::vector<Ray> primary = primary_rays(bounds, o.rays), incoherent = incoherent_rays(bounds, o.rays);
  const std::vector<Ray> few_primary = primary_rays(bounds, o.naive_rays), few_incoherent = incoherent_rays(bounds, o.naive_rays);

  for (int threads : o.threads) {
    // Rounds of every subject in turn, so a slow spell of this shared machine falls on all of them
    // alike; each cell is its median over the rounds.
    std::vector<std::vector<std::pair<RayRates, RayRates>>> rounds(subjects.size());  // primary, incoherent
    for (int round = 0; round < o.repeats; ++round) {
      for (std::size_t i = 0; i < subjects.size(); ++i) {
        const Subject& s = subjects[i];
        const bool few = s.rays != o.rays;
        const ForcedTraversalIsa forced(s.isa);
        rounds[i].emplace_back(measure(few ? few_primary : primary, threads, s.closest, s.any, &s.packets),
                               measure(few ? few_incoherent : incoherent, threads, s.closest, s.any));
      }
    }
    std::vector<std::pair<RayRates, RayRates>> rates;
    for (const auto& runs : rounds) {
      const auto cell = [&](auto pick) {
        std::vector<double> values;
        for (const auto& run : runs) values.push_back(pick(run));
        return bench::median(values);
      };
      std::pair<RayRates, RayRates> r = runs.front();  // the hit counts, the same every round
      r.first.closest = cell([](const auto& run) { return run.first.closest; });
      r.first.any = cell([](const auto& run) { return run.first.any; });
      r.second.closest = cell([](const auto& run) { return run.second.closest; });
      r.second.any = cell([](const auto& run) { return run.second.any; });
      r.first.packet = cell([](const auto& run) { return run.first.packet; });
      r.first.packet_any = cell([](const auto& run) { return run.first.packet_any; });
      rates.push_back(r);
    }
    fmt::print("\n{}: {} triangles, {} object(s); {} rays per set ({} for naive), {} thread{}, Mrays/s (median of {})\n",
               name, prepared.triangle_count(), prepared.objects().size(), o.rays, o.naive_rays, threads,
               threads == 1 ? "" : "s", o.repeats);
    fmt::print("{:<24} {:>9} {:>16} {:>12} {:>19} {:>15} {:>14} {:>14}\n", "accel", "build ms", "primary closest",
               "primary any", "incoherent closest", "incoherent any", "primary x8", "primary any x8");
    for (std::size_t i = 0; i < subjects.size(); ++i) {
      const auto& [p, n] = rates[i];
      fmt::print("{:<24} {:>9.2f} {:>16.2f} {:>12.2f} {:>19.2f} {:>15.2f} {:>14.2f} {:>14.2f}\n", subjects[i].name,
                 subjects[i].build_ms, p.closest, p.any, n.closest, n.any, p.packet, p.packet_any);
    }
    // Ours against the farm's Embree adapter (index 2), and against Embree called directly (last).
    const std::size_t direct = subjects.size() - 1;
    for (const std::size_t anchor : {std::size_t{2}, direct}) {
      for (std::size_t i = 0; i < 2; ++i) {
        const auto& [p, n] = rates[i];
        const auto& [ap, an] = rates[anchor];
        fmt::print("{:<24} {:>9} {:>15.2f}x {:>11.2f}x {:>18.2f}x {:>14.2f}x {:>13.2f}x {:>13.2f}x\n",
                   subjects[i].name + "/" + subjects[anchor].name, "", p.closest / ap.closest, p.any / ap.any,
                   n.closest / an.closest, n.any / an.any, p.packet / ap.packet, p.packet_any / ap.packet_any);
      }
    }
    // Each round's own bvh/embree-direct, its two timings a few seconds apart: how far one round
    // of this machine strays from the ratio of the medians above (a shared machine's slow spells
    // move a single cell by 10-20%), so that a ratio near a target is read with its spread.
    const auto round_spread = [&](auto pick) {
      double low = INFINITY, high = 0.0;
      for (std::size_t r = 0; r < rounds[0].size(); ++r) {
        const double ratio = pick(rounds[0][r]) / pick(rounds[direct][r]);
        low = std::min(low, ratio);
        high = std::max(high, ratio);
      }
      return fmt::format("{:.2f}-{:.2f}x", low, high);
    };
    fmt::print("{:<24} {:>9} {:>16} {:>12} {:>19} {:>15} {:>14} {:>14}\n",
               subjects[0].name + "/" + subjects[direct].name + ", rounds", "",
               round_spread([](const auto& run) { return run.first.closest; }),
               round_spread([](const auto& run) { return run.first.any; }),
               round_spread([](const auto& run) { return run.second.closest; }),
               round_spread([](const auto& run) { return run.second.any; }),
               round_spread([](const auto& run) { return run.first.packet; }),
               round_spread([](const auto& run) { return run.first.packet_any; }));
    // Packets find each ray's own hit: the same rays hit as one by one, for every structure.
    for (std::size_t i = 0; i < subjects.size(); ++i) {
      const RayRates& p = rates[i].first;
      if (p.packet_hits != p.closest_hits || p.packet_any_hits != p.any_hits) {
        throw std::runtime_error(fmt::format("{}: {} hit {} and blocked {} primary rays one by one but {} and {} in packets",
                                             name, subjects[i].name, p.closest_hits, p.any_hits, p.packet_hits,
                                             p.packet_any_hits));
      }
    }
    // The anchor traced the same scene: its hits are ours, to Embree's agreement tests' tolerance.
    const auto agree = [](std::uint64_t a, std::uint64_t b, std::uint64_t rays) {
      return static_cast<double>(a > b ? a - b : b - a) <= 1e-4 * static_cast<double>(rays) + 1.0;
    };
    if (!agree(rates[0].first.closest_hits, rates[direct].first.closest_hits, o.rays) ||
        !agree(rates[0].second.closest_hits, rates[direct].second.closest_hits, o.rays)) {
      throw std::runtime_error(fmt::format("{}: embree-direct hit {} and {} rays, bvh {} and {}: not the same scene",
                                           name, rates[direct].first.closest_hits, rates[direct].second.closest_hits,
                                           rates[0].first.closest_hits, rates[0].second.closest_hits));
    }
  }
}

std::shared_ptr<const Model> load(const std::filesystem::path& file) {
  if (!std::filesystem::exists(file)) {
    throw InputError(fmt::format("{}: no such model (pass --assets DIR, the lab's assets folder)",
                                 file.string()));
  }
  return std::make_shared<const Model>(load_model(file));
}

Scene single(const std::shared_ptr<const Model>& model) {
  Scene scene;
  SceneObject object;
  object.name = model->source.stem().string();
  object.model = model;
  object.materials = model->materials;
  scene.objects.push_back(object);
  return scene;
}

}  // namespace

void run_rt_bench(const RtBenchOptions& options) {
  if (!options.models.empty()) {
    fmt::print("farm bench rt ({})\n", bench::machine_summary());
    for (const std::filesystem::path& model : options.models) {
      bench_scene(model.filename().string(), single(load(model)), options, false);
    }
    return;
  }
  const std::filesystem::path assets =
      options.assets.empty() ? bench::default_cow_path().parent_path().parent_path() : options.assets;
  const auto cow = load(assets / "dae/cow.dae");
  fmt::print("farm bench rt ({}), models from {}\n", bench::machine_summary(), assets.string());
  bench_scene("cow.dae", single(cow), options, true);
  bench_scene("bunny.dae", single(load(assets / "dae/bunny.dae")), options, false);
  bench_scene("CBbunny.dae", single(load(assets / "dae/CBbunny.dae")), options, false);
  bench_scene("cow-grid-100", bench::cow_grid(cow, 10), options, false);
}

}  // namespace farm
