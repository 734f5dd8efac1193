// Micro-benchmarks of the I/O and frame conversion on a fixed VGA frame.
#include <benchmark/benchmark.h>

#include <cmath>

#include "viewpose/core/depth_image.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/io/pcd.hpp"

namespace {

using namespace viewpose;

// A tilted plane 0.8 to 1.6 m away with a missing band: a VGA frame with holes, like a real one.
DepthImage vga_frame() {
  DepthImage d(640, 480);
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      if (u % 97 < 3) continue;
      d.at(u, v) = 0.8f + 0.8f * static_cast<float>(v) / 480.0f + 0.0005f * static_cast<float>(u % 13);
    }
  }
  return d;
}

void BM_DepthToCloud(benchmark::State& state) {
  const DepthImage d = vga_frame();
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  for (auto _ : state) benchmark::DoNotOptimize(depth_to_cloud(d, K));
}
BENCHMARK(BM_DepthToCloud)->Unit(benchmark::kMillisecond);

void BM_DecodeDepthPng(benchmark::State& state) {
  const auto bytes = encode_depth_png(vga_frame(), 0.001);
  for (auto _ : state) benchmark::DoNotOptimize(decode_depth_png(bytes, "bench", 0.001));
}
BENCHMARK(BM_DecodeDepthPng)->Unit(benchmark::kMillisecond);

void BM_ParsePcd(benchmark::State& state) {
  const auto encoding = static_cast<PcdEncoding>(state.range(0));
  const auto bytes = encode_pcd(depth_to_cloud(vga_frame(), CameraIntrinsics::kinect_v1()), encoding);
  state.SetLabel(std::string(to_string(encoding)));
  for (auto _ : state) benchmark::DoNotOptimize(parse_pcd(bytes, "bench"));
}
BENCHMARK(BM_ParsePcd)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
