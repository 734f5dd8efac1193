#include "viewpose/describe/describe.hpp"

#include "viewpose/core/threads.hpp"
#include "viewpose/core/stopwatch.hpp"

namespace viewpose {

Description describe(PointCloud points, const DescribeOptions& options, DescribeTimes* times) {
  auto t = Clock::now();
  PointCloud cloud = PointCloud::from_points(std::move(points.points));
  estimate_normals(cloud, options.normals);
  // Keep only points with a normal: they are the ones every later stage can use.
  PointCloud kept;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.normals[i].allFinite()) continue;
    kept.points.push_back(cloud.points[i]);
    kept.normals.push_back(cloud.normals[i]);
    kept.curvature.push_back(cloud.curvature[i]);
  }
  kept.width = static_cast<int>(kept.points.size());
  Description d;
  for (const auto& p : kept.points) d.centroid += p;
  if (!kept.points.empty()) d.centroid /= static_cast<float>(kept.points.size());
  if (times) times->normals_ms += ms_since(t);
  // VFH and CRH depend only on the points and normals: computed side by side.
  double vfh_ms = 0, crh_ms = 0;
  FirstException failed;
#pragma omp parallel sections num_threads(2)
  {
#pragma omp section
    failed.run(0, [&] {
      const auto tv = Clock::now();
      d.vfh = compute_vfh(kept.points, kept.normals, options.vfh);
      vfh_ms = ms_since(tv);
    });
#pragma omp section
    failed.run(1, [&] {
      const auto tc = Clock::now();
      d.crh = compute_crh(kept.normals, d.centroid);
      crh_ms = ms_since(tc);
    });
  }
  failed.rethrow();
  if (times) {
    times->vfh_ms += vfh_ms;
    times->crh_ms += crh_ms;
  }
  d.cloud = std::move(kept);
  return d;
}

}  // namespace viewpose
