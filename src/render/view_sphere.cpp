#include "viewpose/render/view_sphere.hpp"

#include <array>
#include <cmath>
#include <map>
#include <utility>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

std::vector<Eigen::Vector3d> view_directions(int subdivisions) {
  if (subdivisions < 0 || subdivisions > 5) {
    throw Error(fmt::format("view sphere: {} subdivisions is out of range (0..5)", subdivisions));
  }
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                    {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<int, 3>> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                           {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                           {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                           {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    const auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      return midpoint[key] = static_cast<int>(v.size() - 1);
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& f : faces) {
      const int ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.insert(next.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    faces = std::move(next);
  }
  std::vector<Eigen::Vector3d> dirs;
  dirs.reserve(faces.size());
  for (const auto& f : faces) {
    dirs.push_back((v[static_cast<std::size_t>(f[0])] + v[static_cast<std::size_t>(f[1])] + v[static_cast<std::size_t>(f[2])]).normalized());
  }
  return dirs;
}

Transform look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = (target - eye).normalized();
  Eigen::Vector3d x = z.cross(up);
  if (x.norm() < 1e-6) x = z.cross(std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);  // image down, so that `up` appears upright
  Eigen::Matrix3d R_object_camera;
  R_object_camera << x, y, z;
  return make_transform(R_object_camera.transpose(), -(R_object_camera.transpose() * eye));
}

std::vector<Transform> view_sphere_poses(const Eigen::Vector3d& centre, double distance_m, int subdivisions) {
  if (!(distance_m > 0)) throw Error(fmt::format("view sphere: distance {} m must be positive", distance_m));
  std::vector<Transform> poses;
  for (const Eigen::Vector3d& d : view_directions(subdivisions)) poses.push_back(look_at(centre + distance_m * d, centre));
  return poses;
}

}  // namespace viewpose
