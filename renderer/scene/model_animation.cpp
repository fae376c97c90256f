#include "renderer/scene/model_animation.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "renderer/scene/model.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

// ---- Where a time falls among the keys ----------------------------------------------------------

// Key `key` alone (before the first key, after the last, or exactly on one), or the interval from
// `key` to `key + 1`, `td` seconds long, at fraction `s` of it.
struct KeySpan {
  std::size_t key = 0;
  bool between = false;
  double s = 0.0;
  double td = 0.0;
};

KeySpan locate(const std::vector<float>& times, double t) {
  if (!(t > times.front())) return {};  // also a NaN time: hold the first key
  if (t >= times.back()) return {times.size() - 1};
  // times.front() < t < times.back(): the first key after t is neither the first nor past the end.
  const auto after = std::upper_bound(times.begin(), times.end(), t,
                                      [](double a, float b) { return a < b; });
  const std::size_t k = static_cast<std::size_t>(after - times.begin()) - 1;
  if (static_cast<double>(times[k]) == t) return {k};
  const double td = static_cast<double>(times[k + 1]) - static_cast<double>(times[k]);
  return {k, true, (t - static_cast<double>(times[k])) / td, td};
}

std::size_t values_per_key(SamplerInterpolation interpolation) {
  return interpolation == SamplerInterpolation::CubicSpline ? 3 : 1;
}

template <class T>
void require_counts(const AnimationSampler& sampler, const std::vector<T>& values) {
  if (sampler.times.empty() ||
      values.size() != values_per_key(sampler.interpolation) * sampler.times.size()) {
    throw std::invalid_argument("animation sampler: " +
                                sampler_problem(sampler, std::is_same_v<T, glm::quat>
                                                             ? AnimationPath::Rotation
                                                             : AnimationPath::Translation));
  }
}

// ---- Interpolation ------------------------------------------------------------------------------

// The cubic Hermite spline of glTF 2.0 appendix C between p0 and p1, with tangents m0 and m1
// already scaled by the key interval.
template <class V>
V hermite(const V& p0, const V& m0, const V& p1, const V& m1, double s) {
  const double s2 = s * s;
  const double s3 = s2 * s;
  return (2.0 * s3 - 3.0 * s2 + 1.0) * p0 + (s3 - 2.0 * s2 + s) * m0 + (-2.0 * s3 + 3.0 * s2) * p1 +
         (s3 - s2) * m1;
}

glm::dvec4 as_dvec4(const glm::quat& q) { return {q.x, q.y, q.z, q.w}; }

glm::quat as_quat(const glm::dvec4& v) {
  return glm::quat(static_cast<float>(v.w), static_cast<float>(v.x), static_cast<float>(v.y),
                   static_cast<float>(v.z));
}

// Unit length; `fallback` (itself normalised) where q has none to scale, as a spline through
// opposing tangents could produce.
glm::quat normalised(const glm::dvec4& q, const glm::quat& fallback) {
  const double len = glm::length(q);
  if (!(len > 1e-12) || !std::isfinite(len)) return glm::normalize(fallback);
  return as_quat(q / len);
}

// Spherical interpolation along the shorter arc (q and -q are the same rotation), as the glTF
// specification's reference implementation does it.
glm::quat slerp_shortest(const glm::quat& a, const glm::quat& b, double s) {
  const glm::dvec4 qa = as_dvec4(a);
  glm::dvec4 qb = as_dvec4(b);
  double d = glm::dot(qa, qb);
  if (d < 0.0) {
    qb = -qb;
    d = -d;
  }
  // Nearly the same rotation: sin(theta) would vanish, and the chord is the arc to rounding.
  if (d > 0.9995) return normalised(qa + s * (qb - qa), a);
  const double theta = std::acos(d);
  const double sin_theta = std::sin(theta);
  const glm::dvec4 q =
      (std::sin((1.0 - s) * theta) / sin_theta) * qa + (std::sin(s * theta) / sin_theta) * qb;
  return normalised(q, a);
}

// ---- Transforms ---------------------------------------------------------------------------------

// T * R * S, built in the order (and so with the rounding) the glTF loader has always baked with.
glm::mat4 trs_matrix(const glm::vec3& t, const glm::quat& r, const glm::vec3& s) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), t);
  m *= glm::mat4_cast(r);
  return glm::scale(m, s);
}

std::string animation_name(const ModelAnimation& animation) {
  return animation.name.empty() ? "animation" : "animation '" + animation.name + "'";
}

std::string node_name(const Model& model, std::size_t i) {
  const std::string& name = model.nodes[i].name;
  return "node " + std::to_string(i) + (name.empty() ? "" : " '" + name + "'");
}

// Sum of squares of every element: the Frobenius norm squared.
double frobenius2(const glm::dmat3& m) {
  double sum = 0.0;
  for (int c = 0; c < 3; ++c) sum += glm::dot(m[c], m[c]);
  return sum;
}

}  // namespace

double ModelAnimation::end_seconds() const {
  double end = 0.0;
  for (const AnimationChannel& c : channels) {
    if (!c.sampler.times.empty()) end = std::max(end, static_cast<double>(c.sampler.times.back()));
  }
  return end;
}

std::string sampler_problem(const AnimationSampler& sampler, AnimationPath path) {
  const std::vector<float>& times = sampler.times;
  if (times.empty()) return "sampler has no keys";
  for (std::size_t i = 0; i < times.size(); ++i) {
    if (!std::isfinite(times[i])) return "sampler key " + std::to_string(i) + " time is not finite";
    if (i > 0 && !(times[i] > times[i - 1])) {
      return "sampler key times are not strictly increasing (key " + std::to_string(i) + " at " +
             std::to_string(times[i]) + " s after key " + std::to_string(i - 1) + " at " +
             std::to_string(times[i - 1]) + " s)";
    }
  }
  const bool rotation = path == AnimationPath::Rotation;
  const std::size_t per_key = values_per_key(sampler.interpolation);
  const std::size_t values = rotation ? sampler.quat_values.size() : sampler.vec3_values.size();
  if (values != per_key * times.size()) {
    return "sampler output has " + std::to_string(values) + " values for " +
           std::to_string(times.size()) + " keys" +
           (per_key == 3 ? " (CUBICSPLINE needs 3 per key: in-tangent, value, out-tangent)" : "");
  }
  for (std::size_t i = 0; i < values; ++i) {
    const bool is_value = per_key == 1 || i % 3 == 1;  // not a tangent
    const std::string which = (is_value ? "value " : "tangent ") + std::to_string(i);
    if (rotation) {
      const glm::quat& q = sampler.quat_values[i];
      if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) ||
          !std::isfinite(q.w)) {
        return "sampler output " + which + " is not finite";
      }
      if (is_value && !(glm::length(q) > 0.0f)) {
        return "sampler output " + which + " is not a unit quaternion";
      }
    } else {
      const glm::vec3& v = sampler.vec3_values[i];
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
        return "sampler output " + which + " is not finite";
      }
    }
  }
  return {};
}

glm::vec3 sample_vec3(const AnimationSampler& sampler, double time_seconds) {
  require_counts(sampler, sampler.vec3_values);
  const std::vector<glm::vec3>& v = sampler.vec3_values;
  const bool cubic = sampler.interpolation == SamplerInterpolation::CubicSpline;
  auto value = [&](std::size_t k) { return cubic ? v[3 * k + 1] : v[k]; };

  const KeySpan span = locate(sampler.times, time_seconds);
  const std::size_t k = span.key;
  if (!span.between || sampler.interpolation == SamplerInterpolation::Step) return value(k);
  if (sampler.interpolation == SamplerInterpolation::Linear) {
    return glm::vec3(glm::mix(glm::dvec3(v[k]), glm::dvec3(v[k + 1]), span.s));
  }
  // CubicSpline: key k's out-tangent and key k+1's in-tangent.
  return glm::vec3(hermite(glm::dvec3(value(k)), span.td * glm::dvec3(v[3 * k + 2]),
                           glm::dvec3(value(k + 1)), span.td * glm::dvec3(v[3 * (k + 1)]),
                           span.s));
}

glm::quat sample_rotation(const AnimationSampler& sampler, double time_seconds) {
  require_counts(sampler, sampler.quat_values);
  const std::vector<glm::quat>& q = sampler.quat_values;
  const bool cubic = sampler.interpolation == SamplerInterpolation::CubicSpline;
  auto value = [&](std::size_t k) { return cubic ? q[3 * k + 1] : q[k]; };

  const KeySpan span = locate(sampler.times, time_seconds);
  const std::size_t k = span.key;
  if (!span.between || sampler.interpolation == SamplerInterpolation::Step) {
    return glm::normalize(value(k));
  }
  if (sampler.interpolation == SamplerInterpolation::Linear) {
    return slerp_shortest(value(k), value(k + 1), span.s);
  }
  // CubicSpline: the spline of the four components, normalised back to a rotation.
  const glm::dvec4 p = hermite(as_dvec4(value(k)), span.td * as_dvec4(q[3 * k + 2]),
                               as_dvec4(value(k + 1)), span.td * as_dvec4(q[3 * (k + 1)]), span.s);
  return normalised(p, value(k));
}

glm::mat4 rest_local_matrix(const ModelNode& node) {
  return node.matrix ? *node.matrix : trs_matrix(node.translation, node.rotation, node.scale);
}

std::vector<glm::mat4> node_world_matrices(const Model& model, const ModelAnimation* animation,
                                           double time_seconds) {
  const std::size_t n = model.nodes.size();
  std::vector<glm::mat4> local(n);
  for (std::size_t i = 0; i < n; ++i) local[i] = rest_local_matrix(model.nodes[i]);

  if (animation != nullptr) {
    struct Trs {
      glm::vec3 translation;
      glm::quat rotation;
      glm::vec3 scale;
      bool animated = false;
    };
    std::vector<Trs> posed(n);
    for (std::size_t i = 0; i < n; ++i) {
      const ModelNode& node = model.nodes[i];
      posed[i] = {node.translation, node.rotation, node.scale, false};
    }
    for (std::size_t c = 0; c < animation->channels.size(); ++c) {
      const AnimationChannel& channel = animation->channels[c];
      const std::string where = animation_name(*animation) + " channel " + std::to_string(c);
      if (channel.node < 0 || static_cast<std::size_t>(channel.node) >= n) {
        throw InputError(where + ": no node " + std::to_string(channel.node));
      }
      const std::size_t i = static_cast<std::size_t>(channel.node);
      if (model.nodes[i].matrix) {
        throw InputError(where + ": " + node_name(model, i) +
                         " has a matrix, and glTF allows no animation of such a node");
      }
      Trs& trs = posed[i];
      trs.animated = true;
      switch (channel.path) {
        case AnimationPath::Translation:
          trs.translation = sample_vec3(channel.sampler, time_seconds);
          break;
        case AnimationPath::Rotation:
          trs.rotation = sample_rotation(channel.sampler, time_seconds);
          break;
        case AnimationPath::Scale: trs.scale = sample_vec3(channel.sampler, time_seconds); break;
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (posed[i].animated) {
        local[i] = trs_matrix(posed[i].translation, posed[i].rotation, posed[i].scale);
      }
    }
  }

  // Parents may come after their children: each node climbs to the nearest ancestor already done
  // (or a root) and the chain is finished top down. A chain longer than the node count has met a
  // node twice, so the hierarchy has a cycle.
  std::vector<glm::mat4> world(n);
  std::vector<bool> done(n, false);
  std::vector<std::size_t> chain;
  for (std::size_t i = 0; i < n; ++i) {
    chain.clear();
    for (std::size_t j = i; !done[j];) {
      chain.push_back(j);
      if (chain.size() > n) {
        throw InputError("the node hierarchy has a cycle through " + node_name(model, i));
      }
      const int parent = model.nodes[j].parent;
      if (parent < 0) break;
      if (static_cast<std::size_t>(parent) >= n) {
        throw InputError(node_name(model, j) + " has no parent " + std::to_string(parent));
      }
      j = static_cast<std::size_t>(parent);
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      const int parent = model.nodes[*it].parent;
      world[*it] = parent < 0 ? local[*it] : world[static_cast<std::size_t>(parent)] * local[*it];
      done[*it] = true;
    }
  }
  return world;
}

std::optional<std::size_t> find_animation(const Model& model, std::string_view name) {
  for (std::size_t i = 0; i < model.animations.size(); ++i) {
    if (model.animations[i].name == name) return i;
  }
  return std::nullopt;
}

bool invertible_for_posing(const glm::mat4& rest_world) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(rest_world[c][r])) return false;
    }
  }
  // The Frobenius condition number |A| |A^-1| of the linear part bounds how much the rounding of
  // the baked positions grows when the rest transform is undone: float's 6e-8 times 1e4 keeps
  // the round trip within about 1e-3 of the mesh's size. It is 3 for any rotation and uniform
  // scale, however small the scale.
  const glm::dmat3 a = glm::dmat3(glm::dmat4(rest_world));
  const double det = glm::determinant(a);
  if (!(std::abs(det) > 0.0) || !std::isfinite(det)) return false;
  const double cond2 = frobenius2(a) * frobenius2(glm::inverse(a));
  return std::isfinite(cond2) && cond2 <= 1e8;
}

std::vector<glm::mat4> rest_to_posed_matrices(const Model& model, const ModelAnimation* animation,
                                              double time_seconds) {
  const std::vector<glm::mat4> rest = node_world_matrices(model, nullptr, 0.0);
  if (animation == nullptr) return std::vector<glm::mat4>(rest.size(), glm::mat4(1.0f));
  const std::vector<glm::mat4> posed = node_world_matrices(model, animation, time_seconds);
  std::vector<glm::mat4> out(rest.size(), glm::mat4(1.0f));
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (posed[i] == rest[i]) continue;  // unmoved: exactly the identity, no rounding
    // A node without meshes (say a group hidden by a zero scale at rest) may be singular: only a
    // mesh that asks for its matrix is an error.
    out[i] = invertible_for_posing(rest[i])
                 ? glm::mat4(glm::dmat4(posed[i]) * glm::inverse(glm::dmat4(rest[i])))
                 : glm::mat4(std::numeric_limits<float>::quiet_NaN());
  }
  return out;
}

glm::mat4 mesh_rest_to_posed(const Mesh& mesh, const std::vector<glm::mat4>& rest_to_posed) {
  if (mesh.node < 0) return glm::mat4(1.0f);
  const glm::mat4& m = rest_to_posed.at(static_cast<std::size_t>(mesh.node));
  if (std::isnan(m[3][3])) {  // an affine matrix's corner is 1 otherwise
    throw InputError("mesh '" + mesh.name + "': the rest transform of node " +
                     std::to_string(mesh.node) + " is singular, so it cannot be posed");
  }
  return m;
}

}  // namespace farm
