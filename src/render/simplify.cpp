#include "viewpose/render/simplify.hpp"

#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

namespace viewpose {

namespace {

// Drops every triangle (of welded indices) that repeats one before it with the same corners in the
// same turn, and those whose corners are not distinct. Meshes exported with each face twice (all
// of the YCB-Video models: 15728 faces, each stored twice on vertices of its own) drew every pixel
// twice and, having each edge four times, never counted as closed, so their back faces were drawn
// too: four times the work of the mesh itself. A face repeated the other way round (a sheet drawn
// from both sides) is kept.
void drop_repeated_triangles(std::vector<unsigned int>& indices) {
  const std::size_t n = indices.size() / 3;
  // Each triangle's corners from the smallest on (the same triangle, the same turn), with its place.
  std::vector<std::pair<std::array<unsigned int, 3>, std::size_t>> keys;
  keys.reserve(n);
  for (std::size_t t = 0; t < n; ++t) {
    std::array<unsigned int, 3> c = {indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]};
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    keys.emplace_back(c, t);
  }
  std::sort(keys.begin(), keys.end());
  std::vector<char> keep(n, 1);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& c = keys[i].first;
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2] || (i > 0 && keys[i - 1].first == c)) keep[keys[i].second] = 0;
  }
  std::size_t kept = 0;  // the rest in their order
  for (std::size_t t = 0; t < n; ++t) {
    if (!keep[t]) continue;
    for (std::size_t k = 0; k < 3; ++k) indices[3 * kept + k] = indices[3 * t + k];
    ++kept;
  }
  indices.resize(3 * kept);
}

}  // namespace

TriangleMesh simplify_for_drawing(const TriangleMesh& mesh, float max_error_m) {
  TriangleMesh out;
  if (mesh.triangles.empty() || mesh.vertices.empty()) {
    out.vertices = mesh.vertices;
    out.triangles = mesh.triangles;
    return out;
  }
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "vertices are read as packed floats");
  const std::size_t index_count = 3 * mesh.triangles.size();
  const auto* indices = mesh.triangles.front().data();
  // Weld: one vertex per distinct position.
  std::vector<unsigned int> remap(mesh.vertices.size());
  const std::size_t unique = meshopt_generateVertexRemap(remap.data(), indices, index_count, mesh.vertices.data(),
                                                         mesh.vertices.size(), sizeof(Eigen::Vector3f));
  std::vector<Eigen::Vector3f> welded(unique);
  meshopt_remapVertexBuffer(welded.data(), mesh.vertices.data(), mesh.vertices.size(), sizeof(Eigen::Vector3f), remap.data());
  std::vector<unsigned int> welded_indices(index_count);
  meshopt_remapIndexBuffer(welded_indices.data(), indices, index_count, remap.data());
  drop_repeated_triangles(welded_indices);
  // Collapse edges until the error would pass the bound. meshoptimizer's error is relative to the
  // mesh's extent, and its quadric metric is not a distance: on a sphere the surface moved up to 1.6
  // times the error asked for (SimplifyForDrawing.ASphereStaysWithinTheBound), so half is asked.
  const float scale = meshopt_simplifyScale(welded.front().data(), welded.size(), sizeof(Eigen::Vector3f));
  const float relative_error = scale > 0 ? 0.5f * max_error_m / scale : 0.0f;
  std::vector<unsigned int> simplified(index_count);
  const std::size_t kept = meshopt_simplify(simplified.data(), welded_indices.data(), welded_indices.size(), welded.front().data(),
                                            welded.size(), sizeof(Eigen::Vector3f), 0, relative_error, 0, nullptr);
  simplified.resize(kept);
  // Only the vertices still in use, in first-use order.
  std::vector<unsigned int> compact(welded.size());
  const std::size_t used = meshopt_optimizeVertexFetchRemap(compact.data(), simplified.data(), simplified.size(), welded.size());
  out.vertices.resize(used);
  meshopt_remapVertexBuffer(out.vertices.data(), welded.data(), welded.size(), sizeof(Eigen::Vector3f), compact.data());
  meshopt_remapIndexBuffer(simplified.data(), simplified.data(), simplified.size(), compact.data());
  out.triangles.resize(simplified.size() / 3);
  for (std::size_t t = 0; t < out.triangles.size(); ++t) {
    out.triangles[t] = {simplified[3 * t], simplified[3 * t + 1], simplified[3 * t + 2]};
  }
  return out;
}

}  // namespace viewpose
