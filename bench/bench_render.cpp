// Rendering and sensor-model cost on a VGA frame.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/sensor_model.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/render/view_sphere.hpp"

namespace {

using namespace viewpose;

void BM_Render100kTriangles(benchmark::State& state) {
  const TriangleMesh mesh = make_sphere(0.1, 158);  // about 100k triangles
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const MeshInstance inst{&mesh, look_at({0, -0.25, 0.45}, {0, 0, 0})};  // the sphere fills a third of the frame
  state.SetLabel(std::to_string(mesh.triangles.size()) + " triangles");
  for (auto _ : state) benchmark::DoNotOptimize(render(std::span(&inst, 1), K));
}
BENCHMARK(BM_Render100kTriangles)->Unit(benchmark::kMillisecond);

void BM_RenderJug80Views(benchmark::State& state) {
  const TriangleMesh jug = make_jug();
  const auto poses = view_sphere_poses(Eigen::Vector3d::Zero(), 0.8, 1);
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  for (auto _ : state) benchmark::DoNotOptimize(render_views(jug, poses, K));
}
BENCHMARK(BM_RenderJug80Views)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SensorModelVga(benchmark::State& state) {
  const TriangleMesh jug = make_jug();
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  TriangleMesh wall = make_box_mesh({6.0f, 6.0f, 0.01f});
  const MeshInstance scene[] = {{&jug, look_at({0, -1.0, 0.3}, {0, 0, 0})},
                                {&wall, make_transform(Eigen::Matrix3d::Identity(), {0, 0, 2.5})}};
  RenderOptions o;
  o.normals = true;
  const RenderedFrame frame = render(scene, K, o);
  std::uint64_t seed = 0;
  for (auto _ : state) benchmark::DoNotOptimize(simulate_sensor(frame, K, SensorModel::kinect_v1(), ++seed));
}
BENCHMARK(BM_SensorModelVga)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
