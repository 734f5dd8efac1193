#include "viewpose/core/mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

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

Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c) {
  // Voronoi regions of the triangle's vertices, edges and face (Ericson, Real-Time Collision
  // Detection, 5.1.5).
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return a;  // degenerate triangle
  return a + ab * (vb / denom) + ac * (vc / denom);
}

double distance_to_surface(const TriangleMesh& mesh, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d q = closest_point_on_triangle(p, mesh.vertices[t[0]].cast<double>(),
                                                        mesh.vertices[t[1]].cast<double>(), mesh.vertices[t[2]].cast<double>());
    best = std::min(best, (q - p).squaredNorm());
  }
  return std::sqrt(best);
}

double mesh_diameter(const TriangleMesh& mesh) {
  const auto& v = mesh.vertices;
  std::vector<std::size_t> candidates;
  if (v.size() <= 20000) {
    candidates.resize(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) candidates[i] = i;
  } else {
    // Fibonacci-sphere directions; the diameter's ends are extreme along their own direction.
    const int n = 1280;
    for (int k = 0; k < n; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / n, r = std::sqrt(1.0 - z * z), phi = k * 2.399963229728653;
      const Eigen::Vector3f d(static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)), static_cast<float>(z));
      std::size_t best = 0;
      for (std::size_t i = 1; i < v.size(); ++i) if (v[i].dot(d) > v[best].dot(d)) best = i;
      candidates.push_back(best);
    }
  }
  double best = 0.0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    for (std::size_t j = i + 1; j < candidates.size(); ++j) {
      best = std::max(best, (v[candidates[i]] - v[candidates[j]]).cast<double>().squaredNorm());
    }
  }
  return std::sqrt(best);
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

int closed_mesh_winding(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) return 0;
  const auto edge = [](std::uint32_t a, std::uint32_t b) { return (static_cast<std::uint64_t>(a) << 32) | b; };
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * mesh.triangles.size());
  double volume = 0;  // six times the signed volume enclosed, by the divergence theorem
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] >= mesh.vertices.size()) return 0;
      edges.push_back(edge(t[k], t[(k + 1) % 3]));
    }
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                          c = mesh.vertices[t[2]].cast<double>();
    volume += a.dot(b.cross(c));
  }
  std::sort(edges.begin(), edges.end());
  // Each directed edge as often as its reverse: the surface has no border, and whatever way a line
  // of sight enters it, it meets a front face first. Edges where four or more triangles meet (a
  // surface pinched to an edge, as simplifying a mesh leaves a few) pass; an edge with a triangle
  // repeated, turned the wrong way or missing does not.
  const auto count = [&](std::uint64_t e) {
    const auto [first, last] = std::equal_range(edges.begin(), edges.end(), e);
    return last - first;
  };
  for (auto it = edges.begin(); it != edges.end();) {
    const auto next = std::upper_bound(it, edges.end(), *it);
    if (next - it != count((*it << 32) | (*it >> 32))) return 0;
    it = next;
  }
  return volume > 0 ? 1 : volume < 0 ? -1 : 0;
}

}  // namespace viewpose
