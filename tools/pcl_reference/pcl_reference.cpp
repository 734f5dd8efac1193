// The PCL side of the descriptor comparison: PCL 1.13 (Debian's libpcl-dev) computes, on the
// points and normals in INPUT.pcd, what viewpose computes itself, and writes the numbers into OUTDIR:
//   vfh_framework.txt  VFHEstimation as PCL's 3d_rec_framework sets it up (bins and distances
//                      normalized, no size component), viewpoint 0, centroid = mean of the points
//   crh.txt            CRHEstimation (90) at that centroid
//   normals_pcl.txt    NormalEstimation on the points alone (radius 0.015 m, viewpoint 0): nx ny nz per point
// This program is only built by `make pcl-fixtures`; PCL is never a dependency of viewpose itself.
#include <pcl/common/centroid.h>
#include <pcl/features/crh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/vfh.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <cstdio>
#include <fstream>
#include <string>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: pcl_reference INPUT.pcd OUTDIR\n");
    return 2;
  }
  pcl::PointCloud<pcl::PointNormal>::Ptr input(new pcl::PointCloud<pcl::PointNormal>);
  if (pcl::io::loadPCDFile(argv[1], *input) != 0) return 1;
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  for (const auto& p : input->points) {
    xyz->push_back(pcl::PointXYZ(p.x, p.y, p.z));
    normals->push_back(pcl::Normal(p.normal_x, p.normal_y, p.normal_z));
  }
  const std::string out = argv[2];
  auto tree = pcl::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();

  pcl::VFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::VFHSignature308> vfh;
  vfh.setInputCloud(xyz);
  vfh.setInputNormals(normals);
  vfh.setSearchMethod(tree);
  vfh.setNormalizeBins(true);
  vfh.setNormalizeDistance(true);
  vfh.setFillSizeComponent(false);
  vfh.setViewPoint(0, 0, 0);
  pcl::PointCloud<pcl::VFHSignature308> vfh_out;
  vfh.compute(vfh_out);
  std::ofstream v(out + "/vfh_framework.txt");
  v.precision(9);
  for (float x : vfh_out[0].histogram) v << x << ' ';
  v << '\n';

  Eigen::Vector4f centroid;
  pcl::compute3DCentroid(*xyz, centroid);
  pcl::CRHEstimation<pcl::PointXYZ, pcl::Normal, pcl::Histogram<90>> crh;
  crh.setInputCloud(xyz);
  crh.setInputNormals(normals);
  crh.setCentroid(centroid);
  pcl::PointCloud<pcl::Histogram<90>> crh_out;
  crh.compute(crh_out);
  std::ofstream c(out + "/crh.txt");
  c.precision(9);
  for (float x : crh_out[0].histogram) c << x << ' ';
  c << '\n';

  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(xyz);
  ne.setSearchMethod(tree);
  ne.setRadiusSearch(0.015);
  ne.setViewPoint(0, 0, 0);
  pcl::PointCloud<pcl::Normal> pcl_normals;
  ne.compute(pcl_normals);
  std::ofstream n(out + "/normals_pcl.txt");
  n.precision(9);
  for (const auto& x : pcl_normals) n << x.normal_x << ' ' << x.normal_y << ' ' << x.normal_z << '\n';
  std::printf("PCL %s: wrote vfh_framework.txt, crh.txt, normals_pcl.txt (%zu points)\n", PCL_VERSION_PRETTY, xyz->size());
  return 0;
}
