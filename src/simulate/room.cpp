#include "viewpose/simulate/room.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/render/shapes.hpp"

namespace viewpose {

namespace {

constexpr double kPi = std::numbers::pi;

// Uniform in [lo, hi]; an empty interval (a piece that only just fits) gives its middle.
double draw(std::mt19937_64& rng, double lo, double hi) {
  return lo < hi ? std::uniform_real_distribution<double>(lo, hi)(rng) : 0.5 * (lo + hi);
}
double draw(std::mt19937_64& rng, const Interval& i) { return draw(rng, i.min, i.max); }
int draw_count(std::mt19937_64& rng, int lo, int hi) { return std::uniform_int_distribution<int>(lo, std::max(lo, hi))(rng); }

// Appends an axis-aligned box, given by its centre and edge lengths, to a mesh of several parts.
void add_box(TriangleMesh& mesh, const Eigen::Vector3d& centre, const Eigen::Vector3d& size) {
  const TriangleMesh box = make_box_mesh(size.cast<float>());
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  for (const auto& v : box.vertices) mesh.vertices.push_back(v + centre.cast<float>());
  for (const auto& t : box.triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

std::shared_ptr<const TriangleMesh> box_between(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  TriangleMesh m;
  add_box(m, 0.5 * (lo + hi), hi - lo);
  return std::make_shared<const TriangleMesh>(std::move(m));
}

// A flat place where unknown objects can stand: a rectangle in its own frame (z = 0 is the
// surface, T_world_support places it), with `clearance` of free height above it.
struct Support {
  Transform T_world_support;
  Footprints spots;
  double clearance = 0;
};

// A flat part of a piece of furniture (a shelf board, a seat, a top), in the furniture's frame.
struct SupportArea {
  Transform T_furniture_support;
  PlanRect area;
  double clearance = 0;
};

// A piece of furniture in its own frame: centred on x, its back at +y (against a wall), its
// front at -y, standing on z = 0.
struct Furniture {
  std::string kind;
  TriangleMesh mesh;
  double width = 0, depth = 0;
  std::vector<SupportArea> supports;
};

Transform lifted(double z) { return make_transform(Eigen::Matrix3d::Identity(), {0, 0, z}); }

Furniture make_shelf(std::mt19937_64& rng) {
  Furniture f{"shelf", {}, draw(rng, 0.6, 1.1), draw(rng, 0.28, 0.4), {}};
  const double h = draw(rng, 1.0, 2.0), t = 0.02;
  const int boards = std::max(2, static_cast<int>(h / draw(rng, 0.3, 0.42)));
  const double w = f.width, d = f.depth;
  add_box(f.mesh, {-w / 2 + t / 2, 0, h / 2}, {t, d, h});  // sides
  add_box(f.mesh, {w / 2 - t / 2, 0, h / 2}, {t, d, h});
  add_box(f.mesh, {0, d / 2 - 0.005, h / 2}, {w - 2 * t, 0.01, h});  // back panel
  const double pitch = (h - t) / boards;
  for (int k = 0; k <= boards; ++k) {
    const double z = k * pitch;  // the board's underside
    add_box(f.mesh, {0, -0.005, z + t / 2}, {w - 2 * t, d - 0.01, t});
    if (k < boards) {
      const PlanRect area{-w / 2 + t, -d / 2, w / 2 - t, d / 2 - 0.01};
      f.supports.push_back({lifted(z + t), area, pitch - t});
    }
  }
  return f;
}

Furniture make_cabinet(std::mt19937_64& rng) {
  Furniture f{"cabinet", {}, draw(rng, 0.4, 1.0), draw(rng, 0.4, 0.6), {}};
  const double h = draw(rng, 0.5, 1.0), w = f.width, d = f.depth;
  add_box(f.mesh, {0, 0.01, 0.04}, {w - 0.04, d - 0.02, 0.08});  // a recessed plinth
  add_box(f.mesh, {0, 0, 0.08 + (h - 0.08) / 2}, {w, d, h - 0.08});
  add_box(f.mesh, {0, -d / 2 - 0.012, h - 0.1}, {std::min(0.15, w / 3), 0.024, 0.02});  // a handle
  f.supports.push_back({lifted(h), {-w / 2, -d / 2, w / 2, d / 2}, 1.0});
  return f;
}

Furniture make_chair(std::mt19937_64& rng) {
  const double s = draw(rng, 0.40, 0.48), seat = draw(rng, 0.42, 0.48), leg = 0.03, back = draw(rng, 0.35, 0.5);
  Furniture f{"chair", {}, s, s, {}};
  for (const double x : {-1.0, 1.0})
    for (const double y : {-1.0, 1.0}) add_box(f.mesh, {x * (s / 2 - leg / 2), y * (s / 2 - leg / 2), (seat - 0.03) / 2}, {leg, leg, seat - 0.03});
  add_box(f.mesh, {0, 0, seat - 0.015}, {s, s, 0.03});
  for (const double x : {-1.0, 1.0}) add_box(f.mesh, {x * (s / 2 - leg / 2), s / 2 - leg / 2, seat + back / 2}, {leg, leg, back});
  add_box(f.mesh, {0, s / 2 - leg / 2, seat + back - 0.1}, {s, 0.02, 0.2});  // the backrest
  f.supports.push_back({lifted(seat), {-s / 2, -s / 2, s / 2, s / 2 - leg}, 0.6});
  return f;
}

Furniture make_carton(std::mt19937_64& rng) {
  Furniture f{"carton", {}, draw(rng, 0.25, 0.6), draw(rng, 0.2, 0.5), {}};
  const double h = draw(rng, 0.15, 0.5);
  add_box(f.mesh, {0, 0, h / 2}, {f.width, f.depth, h});
  f.supports.push_back({lifted(h), {-f.width / 2, -f.depth / 2, f.width / 2, f.depth / 2}, 1.0});
  return f;
}

bool overlaps(const PlanRect& a, const PlanRect& b) { return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1; }

PlanRect around(double x, double y, double r) { return {x - r, y - r, x + r, y + r}; }

}  // namespace

double PlanRect::distance(double x, double y) const {
  const double dx = std::max({x0 - x, 0.0, x - x1}), dy = std::max({y0 - y, 0.0, y - y1});
  return std::hypot(dx, dy);
}

Transform standing_at(double x, double y, double z, double yaw) {
  return make_transform(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(), Eigen::Vector3d(x, y, z));
}

bool Footprints::is_free(const Disc& d) const {
  if (d.x - d.r < area_.x0 || d.x + d.r > area_.x1 || d.y - d.r < area_.y0 || d.y + d.r > area_.y1) return false;
  for (const Disc& o : discs_) {
    if (std::hypot(d.x - o.x, d.y - o.y) < d.r + o.r - 1e-9) return false;
  }
  return true;
}

std::optional<Footprints::Disc> Footprints::place(double r, bool touching, std::mt19937_64& rng,
                                                  const std::function<bool(const Disc&)>& allowed, int attempts) {
  if (2 * r > area_.x1 - area_.x0 || 2 * r > area_.y1 - area_.y0) return std::nullopt;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    Disc d{0, 0, r};
    if (!touching || discs_.empty()) {
      d.x = draw(rng, area_.x0 + r, area_.x1 - r);
      d.y = draw(rng, area_.y0 + r, area_.y1 - r);
    } else {
      // Beside a placed disc, 0 to 5 mm apart: objects in a pile touch and hide each other.
      const Disc& other = discs_[std::uniform_int_distribution<std::size_t>(0, discs_.size() - 1)(rng)];
      const double phi = draw(rng, 0, 2 * kPi), gap = r + other.r + draw(rng, 0, 0.005);
      d.x = other.x + gap * std::cos(phi);
      d.y = other.y + gap * std::sin(phi);
    }
    if (is_free(d) && (!allowed || allowed(d))) {
      discs_.push_back(d);
      return d;
    }
  }
  return std::nullopt;
}

std::optional<Footprints::Disc> Footprints::place_around(double r, double x, double y, double spread, std::mt19937_64& rng,
                                                         int attempts) {
  for (int attempt = 0; attempt < attempts; ++attempt) {
    const double phi = draw(rng, 0, 2 * kPi), rho = spread * std::sqrt(draw(rng, 0, 1));
    const Disc d{x + rho * std::cos(phi), y + rho * std::sin(phi), r};
    if (is_free(d)) {
      discs_.push_back(d);
      return d;
    }
  }
  return std::nullopt;
}

Distractor standing_distractor(const TriangleMesh& mesh) {
  if (mesh.vertices.empty()) throw Error("distractor: the mesh is empty");
  TriangleMesh m = mesh;
  m.normals.clear();
  const BoundingBox box = bounding_box(m);
  const Eigen::Vector3f shift(-0.5f * (box.min.x() + box.max.x()), -0.5f * (box.min.y() + box.max.y()), -box.min.z());
  Distractor d;
  for (auto& v : m.vertices) {
    v += shift;
    d.radius = std::max(d.radius, std::hypot(static_cast<double>(v.x()), static_cast<double>(v.y())));
    d.height = std::max(d.height, static_cast<double>(v.z()));
  }
  d.mesh = std::make_shared<const TriangleMesh>(std::move(m));
  return d;
}

TriangleMesh make_blob(double radius, double bumpiness, std::mt19937_64& rng) {
  if (!(radius > 0) || !(bumpiness >= 0 && bumpiness < 0.5)) throw Error("blob: radius must be positive and bumpiness below 0.5");
  TriangleMesh mesh = make_sphere(1.0, 16);
  // Three waves along random directions: smooth, no two blobs alike, never self-intersecting
  // (the radius stays within 1 +- bumpiness of the sphere's).
  struct Wave { Eigen::Vector3d direction; double frequency, phase, amplitude; };
  std::vector<Wave> waves;
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d w(gauss(rng), gauss(rng), gauss(rng));
    waves.push_back({w.normalized(), draw(rng, 1.5, 3.5), draw(rng, 0, 2 * kPi), bumpiness * draw(rng, 0.3, 1.0) / 3});
  }
  const Eigen::Vector3d stretch(draw(rng, 0.75, 1.3), draw(rng, 0.75, 1.3), draw(rng, 0.75, 1.3));
  for (auto& v : mesh.vertices) {
    const Eigen::Vector3d n = v.cast<double>();
    double f = 1.0;
    for (const Wave& w : waves) f += w.amplitude * std::sin(w.frequency * w.direction.dot(n) + w.phase);
    v = (radius * f * n.cwiseProduct(stretch)).cast<float>();
  }
  return mesh;
}

Distractor make_distractor(std::mt19937_64& rng, const std::vector<Distractor>& others, double max_radius, double max_height) {
  if (max_radius < 0.025 || max_height < 0.03) return {};
  const int kinds = others.empty() ? 3 : 4;
  const int kind = std::uniform_int_distribution<int>(0, kinds - 1)(rng);
  if (kind == 3) {
    const Distractor& d = others[std::uniform_int_distribution<std::size_t>(0, others.size() - 1)(rng)];
    if (d.radius <= max_radius && d.height <= max_height) return d;
  }
  const double h_max = std::min(max_height, 0.35);
  if (kind == 0 || kind == 3) {  // a box (also when the chosen mesh does not fit)
    double sx = draw(rng, 0.04, 0.3), sy = draw(rng, 0.04, 0.3);
    const double scale = std::min(1.0, 2 * max_radius / std::hypot(sx, sy));
    sx *= scale;
    sy *= scale;
    TriangleMesh box = make_box_mesh(Eigen::Vector3f(static_cast<float>(sx), static_cast<float>(sy), static_cast<float>(draw(rng, 0.03, h_max))));
    return standing_distractor(box);
  }
  if (kind == 1) {  // a cylinder: a can, a vase, a bin
    const double r = draw(rng, 0.02, std::min(0.12, max_radius));
    return standing_distractor(make_can(r, draw(rng, 0.04, h_max), 40));
  }
  // A smooth blob: a bag, a toy, a fruit. Its stretched radius reaches 1.3 x 1.15 of the drawn one.
  const double r = draw(rng, 0.04, std::max(0.04, std::min(0.14, std::min(max_radius, h_max / 2) / 1.5)));
  Distractor d = standing_distractor(make_blob(r, 0.3, rng));
  return d.radius <= max_radius && d.height <= max_height ? d : Distractor{};
}

Room make_room(const RoomOptions& o, std::uint64_t seed) {
  for (const Interval* i : {&o.back_wall_m, &o.side_wall_m, &o.table_height_m, &o.table_width_m, &o.table_depth_m,
                            &o.table_near_edge_m, &o.table_centre_x_m}) {
    if (!(i->min <= i->max)) throw Error("room: an interval's minimum exceeds its maximum");
  }
  if (!(o.back_wall_m.min > 0.5 && o.side_wall_m.min > 0.5 && o.table_height_m.min > 0.2 && o.table_width_m.min > 0.2 &&
        o.table_depth_m.min > 0.2 && o.ceiling_height_m > o.table_height_m.max + 0.5)) {
    throw Error("room: walls, table and ceiling must leave room for the camera and the table");
  }
  if (o.min_furniture < 0 || o.max_furniture < o.min_furniture || o.min_off_table_distractors < 0 ||
      o.max_off_table_distractors < o.min_off_table_distractors) {
    throw Error("room: bad furniture or distractor counts");
  }
  std::mt19937_64 rng(seed);
  Room room;
  const double table_height = draw(rng, o.table_height_m);
  room.floor_z = -table_height;
  room.ceiling_z = room.floor_z + o.ceiling_height_m;

  // The table: drawn, then grown to cover what must stand on it.
  const double width = draw(rng, o.table_width_m), depth = draw(rng, o.table_depth_m);
  const double near = draw(rng, o.table_near_edge_m), cx = draw(rng, o.table_centre_x_m);
  PlanRect top{cx - width / 2, near, cx + width / 2, near + depth};
  if (o.table_must_cover) {
    const PlanRect& c = *o.table_must_cover;
    top = {std::min(top.x0, c.x0 - 0.1), std::min(top.y0, c.y0 - 0.1), std::max(top.x1, c.x1 + 0.1), std::max(top.y1, c.y1 + 0.1)};
  }
  room.table_top = top;

  // Walls beyond the table, at the distances drawn (farther only if the table reaches there).
  room.back_wall_y = std::max(draw(rng, o.back_wall_m), top.y1 + 0.3);
  room.left_wall_x = -std::max(draw(rng, o.side_wall_m), -top.x0 + 0.3);
  room.right_wall_x = std::max(draw(rng, o.side_wall_m), top.x1 + 0.3);
  const double behind_y = -1.5, wall = 0.1;  // a wall behind the camera closes the room for cameras turned aside
  const double L = room.left_wall_x, R = room.right_wall_x, B = room.back_wall_y, F = room.floor_z, C = room.ceiling_z;
  room.meshes.push_back({"floor", box_between({L - wall, behind_y - wall, F - 0.05}, {R + wall, B + wall, F}), Transform::Identity()});
  room.meshes.push_back({"ceiling", box_between({L - wall, behind_y - wall, C}, {R + wall, B + wall, C + 0.05}), Transform::Identity()});
  room.meshes.push_back({"wall", box_between({L - wall, B, F}, {R + wall, B + wall, C}), Transform::Identity()});
  room.meshes.push_back({"wall", box_between({L - wall, behind_y - wall, F}, {L, B + wall, C}), Transform::Identity()});
  room.meshes.push_back({"wall", box_between({R, behind_y - wall, F}, {R + wall, B + wall, C}), Transform::Identity()});
  room.meshes.push_back({"wall", box_between({L - wall, behind_y - wall, F}, {R + wall, behind_y, C}), Transform::Identity()});

  {  // A 3 cm top on four legs, with an apron under its edges, as dining and office tables are.
    TriangleMesh table;
    const double t = 0.03, leg = 0.05, inset = 0.06, apron = 0.08;
    add_box(table, {0.5 * (top.x0 + top.x1), 0.5 * (top.y0 + top.y1), -t / 2}, {top.x1 - top.x0, top.y1 - top.y0, t});
    for (const double x : {top.x0 + inset, top.x1 - inset})
      for (const double y : {top.y0 + inset, top.y1 - inset}) add_box(table, {x, y, (F - t) / 2}, {leg, leg, -F - t});
    const double ax0 = top.x0 + inset, ax1 = top.x1 - inset, ay0 = top.y0 + inset, ay1 = top.y1 - inset;
    add_box(table, {0.5 * (ax0 + ax1), ay0, -t - apron / 2}, {ax1 - ax0, 0.02, apron});
    add_box(table, {0.5 * (ax0 + ax1), ay1, -t - apron / 2}, {ax1 - ax0, 0.02, apron});
    add_box(table, {ax0, 0.5 * (ay0 + ay1), -t - apron / 2}, {0.02, ay1 - ay0, apron});
    add_box(table, {ax1, 0.5 * (ay0 + ay1), -t - apron / 2}, {0.02, ay1 - ay0, apron});
    room.meshes.push_back({"table", std::make_shared<const TriangleMesh>(std::move(table)), Transform::Identity()});
  }

  // Furniture on the floor, none overlapping another, the table or the space between the camera
  // and the table (a real camera there would see nothing else).
  std::vector<PlanRect> taken = {{top.x0 - 0.1, top.y0 - 0.1, top.x1 + 0.1, top.y1 + 0.1}, {-0.8, behind_y, 0.8, top.y0}};
  std::vector<Support> supports;
  const int furniture = draw_count(rng, o.min_furniture, o.max_furniture);
  for (int n = 0; n < furniture; ++n) {
    const int kind = std::uniform_int_distribution<int>(0, 3)(rng);
    Furniture f = kind == 0 ? make_shelf(rng) : kind == 1 ? make_cabinet(rng) : kind == 2 ? make_chair(rng) : make_carton(rng);
    for (int attempt = 0; attempt < 50; ++attempt) {
      double x = 0, y = 0, yaw = 0;
      PlanRect plan;
      if (f.kind == "shelf" || f.kind == "cabinet") {  // its back to a wall: the back one or a side one
        // Half of them on the wall the camera faces, where a fixed camera sees them; the others on
        // a side wall, ahead of the camera.
        const int side = draw(rng, 0, 1) < 0.5 ? 0 : (draw(rng, 0, 1) < 0.5 ? 1 : 2);
        if (side == 0) {
          x = draw(rng, L + f.width / 2, R - f.width / 2);
          y = B - f.depth / 2;
          plan = {x - f.width / 2, y - f.depth / 2, x + f.width / 2, B};
        } else {
          y = draw(rng, std::min(1.0, B - f.width / 2), B - f.width / 2);
          x = side == 1 ? L + f.depth / 2 : R - f.depth / 2;
          yaw = side == 1 ? kPi / 2 : -kPi / 2;
          plan = {x - f.depth / 2, y - f.width / 2, x + f.depth / 2, y + f.width / 2};
        }
      } else {  // anywhere on the floor, turned anyhow; a chair often at the table, facing it
        const double r = 0.5 * std::hypot(f.width, f.depth);
        if (f.kind == "chair" && draw(rng, 0, 1) < 0.6) {
          const int side = std::uniform_int_distribution<int>(0, 2)(rng);  // far edge, left, right
          if (side == 0) {
            x = draw(rng, top.x0 + r, top.x1 - r);
            y = top.y1 + r + 0.12;
            yaw = 0;
          } else {
            x = side == 1 ? top.x0 - r - 0.12 : top.x1 + r + 0.12;
            y = draw(rng, top.y0 + r, top.y1 - r);
            yaw = side == 1 ? kPi / 2 : -kPi / 2;
          }
          yaw += draw(rng, -0.25, 0.25);
        } else {
          x = draw(rng, L + r, R - r);
          y = draw(rng, 0.3, B - r);
          yaw = draw(rng, 0, 2 * kPi);
        }
        plan = around(x, y, r);
      }
      const bool inside = plan.x0 >= L - 1e-9 && plan.x1 <= R + 1e-9 && plan.y1 <= B + 1e-9 && plan.y0 >= behind_y;
      const bool clear = inside && std::none_of(taken.begin(), taken.end(), [&](const PlanRect& t) { return overlaps(t, plan); });
      if (!clear) continue;
      taken.push_back(plan);
      const Transform T_world_furniture = standing_at(x, y, F, yaw);
      for (const SupportArea& a : f.supports) supports.push_back({T_world_furniture * a.T_furniture_support, Footprints(a.area), a.clearance});
      room.meshes.push_back({f.kind, std::make_shared<const TriangleMesh>(std::move(f.mesh)), T_world_furniture});
      ++room.furniture;
      break;
    }
  }

  // Unknown objects off the table: on the floor, the shelves, cabinets, chairs and cartons.
  std::vector<Distractor> others;
  for (const auto& m : o.distractor_meshes) others.push_back(standing_distractor(*m));
  Footprints floor({L, behind_y, R, B});
  const int off_table = draw_count(rng, o.min_off_table_distractors, o.max_off_table_distractors);
  for (int n = 0; n < off_table; ++n) {
    const bool on_floor = supports.empty() || draw(rng, 0, 1) < 0.4;
    Support* s = on_floor ? nullptr : &supports[std::uniform_int_distribution<std::size_t>(0, supports.size() - 1)(rng)];
    const PlanRect area = on_floor ? PlanRect{L, behind_y, R, B} : s->spots.area();
    const double max_r = std::min({0.25, 0.5 * (area.x1 - area.x0), 0.5 * (area.y1 - area.y0)});
    const Distractor d = make_distractor(rng, others, max_r, on_floor ? 0.5 : s->clearance - 0.02);
    if (!d.mesh) continue;
    std::optional<Footprints::Disc> spot;
    if (on_floor) {
      spot = floor.place(d.radius, false, rng, [&](const Footprints::Disc& disc) {
        const PlanRect plan = around(disc.x, disc.y, disc.r);
        return std::none_of(taken.begin(), taken.end(), [&](const PlanRect& t) { return overlaps(t, plan); });
      });
    } else {
      spot = s->spots.place(d.radius, false, rng);
    }
    if (!spot) continue;
    const Transform T_world_support = on_floor ? standing_at(0, 0, F, 0) : s->T_world_support;
    room.meshes.push_back({"distractor", d.mesh, T_world_support * standing_at(spot->x, spot->y, 0, draw(rng, 0, 2 * kPi))});
    ++room.off_table_distractors;
  }
  room.description = fmt::format(
      "room: walls {:.2f} m ahead, {:.2f} m left, {:.2f} m right; table {:.2f} x {:.2f} m, top {:.2f} m above the floor; "
      "{} pieces of furniture, {} unknown objects off the table",
      B, -L, R, top.x1 - top.x0, top.y1 - top.y0, table_height, room.furniture, room.off_table_distractors);
  return room;
}

}  // namespace viewpose
