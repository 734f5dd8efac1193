#pragma once
// A mesh for drawing at a known depth tolerance: CAD and scanned meshes often hold tens of
// thousands of triangles where a few hundred draw the same depth to within a couple of millimetres,
// and verification draws a model for every hypothesis. Positions are welded first (texture seams split
// vertices that share a position, and a seam would stop edges from collapsing), then edges are
// collapsed while the surface moves less than `max_error_m` (meshoptimizer's quadric simplifier).
#include "viewpose/core/mesh.hpp"

namespace viewpose {

/// `mesh` with vertices at the same position welded and as few triangles as keep every point of the
/// surface within `max_error_m` of the original (measured on a sphere: 0.8 to 0.9 of it). Normals
/// are dropped (drawing depth needs none). Orientation is kept: a closed, consistently wound mesh
/// stays so.
TriangleMesh simplify_for_drawing(const TriangleMesh& mesh, float max_error_m);

}  // namespace viewpose
