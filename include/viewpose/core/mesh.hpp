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

/// Whether the mesh is closed and consistently wound (every edge run along by as many triangles in
/// one direction as in the other: two, or more where the surface is pinched to an edge): +1 with its triangles wound counter-clockwise seen
/// from outside (positive enclosed volume), -1 wound the other way, 0 not closed. Only a closed
/// mesh may have its back faces skipped when drawn: they are always hidden by its front faces.
int closed_mesh_winding(const TriangleMesh& mesh);

/// The point of triangle (a, b, c) closest to p.
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c);

/// Distance from p to the nearest point of the mesh's surface (every triangle is tried).
double distance_to_surface(const TriangleMesh& mesh, const Eigen::Vector3d& p);

/// The largest distance between two vertices (BOP's "diameter"). Exact up to 20,000 vertices;
/// beyond that the extreme vertices along 1,280 directions are compared, within 0.2 % of exact.
double mesh_diameter(const TriangleMesh& mesh);

/// An axis-aligned box centred on the origin with the given edge lengths (12 triangles, outward
/// winding). A small analytic shape for tests and demos.
TriangleMesh make_box_mesh(const Eigen::Vector3f& size);

}  // namespace viewpose
