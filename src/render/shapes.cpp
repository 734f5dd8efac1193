#include "viewpose/render/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

namespace {

constexpr double kPi = std::numbers::pi;

// Appends a grid of rings: ring(i, j) for i = 0..rings-1 along the surface and j = 0..around-1
// around it (closed around), joined by quads split into two triangles.
void add_tube(TriangleMesh& mesh, int rings, int around, const std::function<Eigen::Vector3d(int, int)>& ring) {
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < around; ++j) mesh.vertices.push_back(ring(i, j).cast<float>());
  const auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(i * around + (j % around)); };
  for (int i = 0; i + 1 < rings; ++i) {
    for (int j = 0; j < around; ++j) {
      mesh.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i + 1, j)});
    }
  }
}

// Closes ring `i` of the last tube (of `around` vertices starting at `first`) with a fan to `centre`.
void add_fan(TriangleMesh& mesh, std::uint32_t first, int around, const Eigen::Vector3d& centre, bool flip) {
  const auto c = static_cast<std::uint32_t>(mesh.vertices.size());
  mesh.vertices.push_back(centre.cast<float>());
  for (int j = 0; j < around; ++j) {
    const std::uint32_t a = first + static_cast<std::uint32_t>(j), b = first + static_cast<std::uint32_t>((j + 1) % around);
    mesh.triangles.push_back(flip ? std::array<std::uint32_t, 3>{c, b, a} : std::array<std::uint32_t, 3>{c, a, b});
  }
}

// A point of the superellipse |x/a|^p + |y/b|^p = 1 at angle t (rounded rectangle for p = 4).
Eigen::Vector2d superellipse(double a, double b, double p, double t) {
  const double c = std::cos(t), s = std::sin(t);
  return {a * std::copysign(std::pow(std::abs(c), 2.0 / p), c), b * std::copysign(std::pow(std::abs(s), 2.0 / p), s)};
}

// A closed cylinder along z from z0 to z1 centred at (cx, cy).
void add_cylinder(TriangleMesh& mesh, double cx, double cy, double radius, double z0, double z1, int segments) {
  const auto first = static_cast<std::uint32_t>(mesh.vertices.size());
  add_tube(mesh, 2, segments, [&](int i, int j) {
    const double t = 2 * kPi * j / segments;
    return Eigen::Vector3d(cx + radius * std::cos(t), cy + radius * std::sin(t), i == 0 ? z0 : z1);
  });
  add_fan(mesh, first, segments, {cx, cy, z0}, true);
  add_fan(mesh, first + static_cast<std::uint32_t>(segments), segments, {cx, cy, z1}, false);
}

// A tube of `thickness` radius swept along an arc in the x-z plane around `centre`, its ends
// closed (so that the whole is a closed surface, whose back faces a renderer may skip).
void add_arc_tube(TriangleMesh& mesh, const Eigen::Vector3d& centre, double radius, double thickness, double from,
                  double to, int steps) {
  const auto first = static_cast<std::uint32_t>(mesh.vertices.size());
  const auto on_arc = [&](double a) { return Eigen::Vector3d(centre + radius * Eigen::Vector3d(std::cos(a), 0, std::sin(a))); };
  add_tube(mesh, steps + 1, 16, [&](int i, int j) {
    const double a = from + (to - from) * i / steps, phi = 2 * kPi * j / 16;
    const Eigen::Vector3d radial(std::cos(a), 0, std::sin(a));
    return Eigen::Vector3d(on_arc(a) + thickness * (std::cos(phi) * radial + std::sin(phi) * Eigen::Vector3d::UnitY()));
  });
  add_fan(mesh, first, 16, on_arc(from), true);
  add_fan(mesh, first + static_cast<std::uint32_t>(steps * 16), 16, on_arc(to), false);
}

}  // namespace

void centre_on_bounding_box(TriangleMesh& mesh) {
  const BoundingBox box = bounding_box(mesh);
  if (box.empty) return;
  const Eigen::Vector3f c = 0.5f * (box.min + box.max);
  for (auto& v : mesh.vertices) v -= c;
}

TriangleMesh make_jug(const JugShape& s) {
  if (!(s.height > 0 && s.width > 0 && s.depth > 0 && s.shoulder > 0 && s.shoulder < 1)) {
    throw Error("jug: height, width and depth must be positive and the shoulder a fraction of the height");
  }
  TriangleMesh mesh;
  const int rings = 40, around = 64;
  const double a = s.width / 2, b = s.depth / 2;
  // The shoulder narrows the body towards the top and slides it towards the cap's side (+x).
  const double top_scale = 0.75, cap_x = 0.15 * a;
  // 0 below the shoulder, rising smoothly (zero slope where it starts) to 1 at the top.
  const auto shoulder_at = [&](double h) {
    const double u = std::clamp((h - (1 - s.shoulder)) / s.shoulder, 0.0, 1.0);
    return 1.0 - std::cos(u * kPi / 2);
  };
  const auto scale_at = [&](double h) { return 1.0 - (1.0 - top_scale) * shoulder_at(h); };
  const auto shift_at = [&](double h) { return cap_x * shoulder_at(h); };
  const auto first = static_cast<std::uint32_t>(mesh.vertices.size());
  add_tube(mesh, rings, around, [&](int i, int j) {
    const double h = static_cast<double>(i) / (rings - 1);
    const double bottom_round = 1.0 - 0.04 * std::pow(std::max(0.0, 1.0 - h * 12.0), 2);  // a rounded base edge
    const double k = scale_at(h) * bottom_round;
    const Eigen::Vector2d p = superellipse(a * k, b * k, 4.0, 2 * kPi * j / around);
    return Eigen::Vector3d(p.x() + shift_at(h), p.y(), h * s.height);
  });
  add_fan(mesh, first, around, {0, 0, 0}, true);
  add_fan(mesh, first + static_cast<std::uint32_t>((rings - 1) * around), around, {shift_at(1.0), 0, s.height}, false);
  // The top spans x in [top_min, top_max]. The cap stands on its +x part; the handle loops over
  // its -x part, both ends sunk below the top surface (an arc from -15 to 195 degrees).
  const double top_min = shift_at(1.0) - a * top_scale, top_max = shift_at(1.0) + a * top_scale;
  const double cap_centre = top_max - s.cap_radius - 0.1 * s.cap_radius;
  add_cylinder(mesh, cap_centre, 0, s.cap_radius, s.height - 0.005, s.height + s.cap_height, 32);
  const double handle_x = top_min + 0.25 * (top_max - top_min);
  const Eigen::Vector3d handle_centre(handle_x, 0, s.height - 0.01);
  add_arc_tube(mesh, handle_centre, s.handle_radius, s.handle_thickness, -kPi / 12, kPi + kPi / 12, 32);
  centre_on_bounding_box(mesh);
  return mesh;
}

TriangleMesh make_can(double radius, double height, int segments) {
  if (!(radius > 0 && height > 0 && segments >= 3)) throw Error("can: radius and height must be positive");
  TriangleMesh mesh;
  add_cylinder(mesh, 0, 0, radius, 0, height, segments);
  centre_on_bounding_box(mesh);
  return mesh;
}

TriangleMesh make_mug(double radius, double height, double wall) {
  if (!(radius > 0 && height > 0 && wall > 0 && wall < radius)) throw Error("mug: sizes must be positive, wall < radius");
  TriangleMesh mesh;
  const int around = 48;
  const double inner = radius - wall;
  // Outer wall, rim, inner wall, as one tube of rings: bottom-out, top-out, top-in, bottom-in.
  const auto first = static_cast<std::uint32_t>(mesh.vertices.size());
  add_tube(mesh, 4, around, [&](int i, int j) {
    const double t = 2 * kPi * j / around;
    const double r = i < 2 ? radius : inner;
    const double z = (i == 0) ? 0 : (i == 3 ? wall : height);
    return Eigen::Vector3d(r * std::cos(t), r * std::sin(t), z);
  });
  add_fan(mesh, first, around, {0, 0, 0}, true);
  add_fan(mesh, first + static_cast<std::uint32_t>(3 * around), around, {0, 0, wall}, false);
  add_arc_tube(mesh, {radius + 0.012, 0, height / 2}, 0.028, 0.006, -0.5 * kPi, 0.5 * kPi, 24);
  centre_on_bounding_box(mesh);
  return mesh;
}

TriangleMesh make_sphere(double radius, int rings) {
  if (!(radius > 0) || rings < 2) throw Error("sphere: radius must be positive and rings at least 2");
  TriangleMesh mesh;
  const int around = 2 * rings;
  add_tube(mesh, rings + 1, around, [&](int i, int j) {
    const double th = kPi * i / rings, ph = 2 * kPi * j / around;
    return Eigen::Vector3d(radius * std::sin(th) * std::cos(ph), radius * std::sin(th) * std::sin(ph), radius * std::cos(th));
  });
  return mesh;
}

std::vector<std::string> shape_names() { return {"jug", "box", "can", "mug"}; }

TriangleMesh make_named_shape(std::string_view name) {
  if (name == "jug") return make_jug();
  if (name == "box") return make_box_mesh({0.06f, 0.095f, 0.20f});
  if (name == "can") return make_can();
  if (name == "mug") return make_mug();
  throw Error(fmt::format("unknown shape '{}' (jug, box, can, mug)", name));
}

}  // namespace viewpose
