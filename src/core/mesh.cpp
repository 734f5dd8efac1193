#include "viewpose/core/mesh.hpp"

#include <Eigen/Geometry>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

void TriangleMesh::check_consistent() const {
  if (!normals.empty() && normals.size() != vertices.size()) {
    throw Error(fmt::format("mesh: {} normals for {} vertices", normals.size(), vertices.size()));
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (std::uint32_t i : triangles[t]) {
      if (i >= vertices.size()) {
        throw Error(fmt::format("mesh: triangle {} names vertex {} of {}", t, i, vertices.size()));
      }
    }
  }
}

double TriangleMesh::surface_area() const {
  double area = 0.0;
  for (const auto& t : triangles) {
    const Eigen::Vector3d a = vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = vertices[t[2]].cast<double>();
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

TriangleMesh make_box_mesh(const Eigen::Vector3f& size) {
  const Eigen::Vector3f h = 0.5f * size;
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  }
  // Two triangles per face, counter-clockwise seen from outside.
  mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},   // -z, +z
                    {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},   // -y, +y
                    {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};  // -x, +x
  return mesh;
}

}  // namespace viewpose
