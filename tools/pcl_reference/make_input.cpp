// Writes the input of the PCL reference run: one rendered view of the built-in jug (view 7 of the
// 80-view sphere, 1 m away, Kinect v1 intrinsics), voxelized and given normals by viewpose exactly
// as `viewpose db build` does. Usage: make_input OUT.pcd
#include <cstdio>

#include "viewpose/database/view_database.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/render/view_sphere.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_input OUT.pcd\n");
    return 2;
  }
  using namespace viewpose;
  const DatabaseParams params;
  const TriangleMesh jug = make_jug();
  const Transform pose = view_sphere_poses(Eigen::Vector3d::Zero(), params.distance_m, params.subdivisions)[7];
  const MeshInstance inst{&jug, pose};
  const RenderedFrame frame = render(std::span(&inst, 1), params.camera);
  PointCloud cloud;
  describe_view(frame.depth, pose, 0, params, &cloud);
  write_pcd(argv[1], cloud, PcdEncoding::BinaryCompressed);
  std::printf("%s: %zu points\n", argv[1], cloud.size());
  return 0;
}
