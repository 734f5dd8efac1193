#include "viewpose/core/kdtree.hpp"

#include <nanoflann.hpp>

namespace viewpose {

namespace {
// nanoflann's view of the finite points.
struct Points {
  std::vector<Eigen::Vector3f> xyz;
  std::vector<std::uint32_t> original;  // index in the caller's span
  std::size_t kdtree_get_point_count() const { return xyz.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const { return xyz[i][static_cast<Eigen::Index>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }
};
using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Points>, Points, 3, std::uint32_t>;
}  // namespace

struct KdTree::Impl {
  Points points;
  std::unique_ptr<Index> index;
};

KdTree::KdTree(std::span<const Eigen::Vector3f> points) : impl_(std::make_unique<Impl>()) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    impl_->points.xyz.push_back(points[i]);
    impl_->points.original.push_back(static_cast<std::uint32_t>(i));
  }
  impl_->index = std::make_unique<Index>(3, impl_->points, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  impl_->index->buildIndex();
}

KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

std::size_t KdTree::size() const { return impl_->points.xyz.size(); }

void KdTree::radius_search(const Eigen::Vector3f& query, float radius, std::vector<std::uint32_t>& indices) const {
  indices.clear();
  if (impl_->points.xyz.empty()) return;
  nanoflann::SearchParams params;
  params.sorted = false;
  thread_local std::vector<std::pair<std::uint32_t, float>> matches;  // per thread: searches run in parallel
  matches.clear();
  impl_->index->radiusSearch(query.data(), radius * radius, matches, params);
  indices.reserve(matches.size());
  for (const auto& m : matches) indices.push_back(impl_->points.original[m.first]);
}

bool KdTree::nearest(const Eigen::Vector3f& query, std::uint32_t& index, float& squared_distance) const {
  if (impl_->points.xyz.empty()) return false;
  std::uint32_t i = 0;
  impl_->index->knnSearch(query.data(), 1, &i, &squared_distance);
  index = impl_->points.original[i];
  return true;
}

bool KdTree::nearest_within(const Eigen::Vector3f& query, float bound_squared, std::uint32_t& index,
                            float& squared_distance) const {
  if (impl_->points.xyz.empty()) return false;
  std::uint32_t i = 0;
  nanoflann::KNNResultSet<float, std::uint32_t> result(1);
  result.init(&i, &squared_distance);
  // The search adds a point only when it is closer than the result's worst distance, and skips
  // branches whose box is farther: starting that distance at the bound instead of infinity.
  squared_distance = bound_squared;
  impl_->index->findNeighbors(result, query.data(), nanoflann::SearchParams());
  if (result.size() == 0) return false;
  index = impl_->points.original[i];
  return true;
}

}  // namespace viewpose
