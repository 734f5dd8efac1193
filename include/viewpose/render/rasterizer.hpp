#pragma once
// A z-buffer rasterizer for depth: triangle meshes placed in the camera frame, rendered at given
// intrinsics. Each pixel is sampled at its centre; depth is interpolated perspective-correctly
// (1/z is affine across a projected triangle), so a planar face renders at its exact depth.
#include <cstdint>
#include <span>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/core/mesh.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

struct MeshInstance {
  const TriangleMesh* mesh = nullptr;
  Transform T_camera_object = Transform::Identity();
};

struct RenderOptions {
  double near_m = 0.01;  ///< triangles are clipped at this depth
  bool normals = false;  ///< also return each pixel's surface normal
  bool instances = true;  ///< also return which instance each pixel shows (verification needs depth only)
  /// Skip the back faces of closed meshes, wound as closed_mesh_winding() says (+1 or -1; 0 draws
  /// every triangle). The picture is the same, drawn in about half the time. Only for closed meshes.
  int closed_winding = 0;
};

struct RenderedFrame {
  DepthImage depth;                    ///< metres along z; NaN where no surface
  std::vector<std::int32_t> instance;  ///< per pixel: index of the instance seen, -1 for none (if asked)
  std::vector<Eigen::Vector3f> normal;  ///< per pixel, camera frame, facing the camera (if asked)
};

/// Renders the nearest surface of all instances at every pixel.
RenderedFrame render(std::span<const MeshInstance> instances, const CameraIntrinsics& K,
                     const RenderOptions& options = {});

/// Points drawn as small squares (for models scanned as a point cloud, with no mesh): each point
/// covers the pixels its `spacing_m` neighbourhood spans at its depth; the nearest point wins.
/// Fills depth and instance (0); no normals.
RenderedFrame render_points(std::span<const Eigen::Vector3f> points, const Transform& T_camera_object,
                            const CameraIntrinsics& K, float spacing_m);

/// One mesh seen from many poses (a view sphere), rendered in parallel.
std::vector<RenderedFrame> render_views(const TriangleMesh& mesh, std::span<const Transform> T_camera_object,
                                        const CameraIntrinsics& K, const RenderOptions& options = {});

}  // namespace viewpose
