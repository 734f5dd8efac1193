#pragma once
// Nearest-neighbour search over 3-D points (nanoflann underneath). Non-finite points are left out;
// every index returned is an index into the span the tree was built on.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace viewpose {

class KdTree {
 public:
  /// Indexes `points`, which must outlive the tree.
  explicit KdTree(std::span<const Eigen::Vector3f> points);
  ~KdTree();
  KdTree(KdTree&&) noexcept;
  KdTree& operator=(KdTree&&) noexcept;

  /// Indices of the points within `radius` of `query` (the query itself included if indexed).
  void radius_search(const Eigen::Vector3f& query, float radius, std::vector<std::uint32_t>& indices) const;
  /// The nearest indexed point; false when the tree is empty.
  bool nearest(const Eigen::Vector3f& query, std::uint32_t& index, float& squared_distance) const;
  /// The nearest indexed point if it lies closer than sqrt(`bound_squared`); false if none does.
  /// The same point nearest() finds, in less time the tighter the bound: branches of the tree
  /// farther than the bound are never entered (a neighbouring query's answer is a good bound).
  bool nearest_within(const Eigen::Vector3f& query, float bound_squared, std::uint32_t& index, float& squared_distance) const;
  std::size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace viewpose
