#pragma once
// A triangle mesh in metres, in the object's own frame.
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3f> normals;  ///< empty, or one per vertex
  std::vector<std::array<std::uint32_t, 3>> triangles;

  /// Throws viewpose::Error when a triangle names a vertex that does not exist, or the normals'
  /// count disagrees with the vertices'.
  void check_consistent() const;
  /// Total area of the triangles in square metres.
  double surface_area() const;
};

inline BoundingBox bounding_box(const TriangleMesh& mesh) { return bounding_box(mesh.vertices); }

/// An axis-aligned box centred on the origin with the given edge lengths (12 triangles, outward
/// winding). A small analytic shape for tests and demos.
TriangleMesh make_box_mesh(const Eigen::Vector3f& size);

}  // namespace viewpose
