#pragma once
// Euclidean cluster extraction (PCL's EuclideanClusterExtraction): points closer than a tolerance
// belong together, transitively. A k-d tree version for any cloud, and an organized version that
// takes neighbours from the image grid of a depth frame (no tree, for real time).
#include <cstdint>
#include <span>
#include <vector>

#include "viewpose/core/point_cloud.hpp"

namespace viewpose {

struct ClusterOptions {
  float tolerance_m = 0.02f;          ///< largest gap inside one object (PCL's typical 2 cm)
  std::size_t min_points = 100;       ///< smaller clusters are dropped (noise, fragments)
  std::size_t max_points = 1000000;   ///< larger ones too (remains of walls and tables)
  int window_px = 2;                  ///< organized version: neighbours within this many pixels
};

using Cluster = std::vector<std::uint32_t>;  ///< indices into the cloud, ascending

/// Clusters among the points `indices` of `cloud`, largest first.
std::vector<Cluster> euclidean_clusters(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                                        const ClusterOptions& options = {});

/// The same on an organized cloud: only the points `indices` take part, and neighbours are looked
/// for within window_px pixels, so gaps wider than that in the image split clusters.
std::vector<Cluster> organized_clusters(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                                        const ClusterOptions& options = {});

}  // namespace viewpose
