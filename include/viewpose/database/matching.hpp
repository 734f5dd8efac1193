#pragma once
// Matching a description against the database: the k views nearest by chi-squared distance,
// exact; by exhaustive search, or through a ViewIndex for large databases.
#include <cstdint>
#include <vector>

#include "viewpose/database/view_database.hpp"

namespace viewpose {

struct Match {
  std::uint32_t view = 0;  ///< index into ViewDatabase::views
  float distance = 0;
};

/// Sum over bins of (a - b)^2 / (a + b), bins where both are 0 skipped (FLANN's ChiSquareDistance).
float chi_squared(const Vfh& a, const Vfh& b);

/// The k nearest views, nearest first (ties by view index).
std::vector<Match> nearest_views(const ViewDatabase& db, const Vfh& query, std::size_t k = 20);

/// Each object's k nearest views, merged and sorted nearest first. With one object this is
/// nearest_views; with many, a small object's views are not crowded out by a larger object's.
std::vector<Match> nearest_views_per_object(const ViewDatabase& db, const Vfh& query, std::size_t k = 20);

/// The same matches as nearest_views_per_object, found without comparing the query with every
/// view in full, so that a database of a thousand objects (80,000 views) answers in about a
/// millisecond. Each view's histogram is also kept coarse (groups of 16 neighbouring bins summed):
/// the chi-squared distance of coarse histograms never exceeds the full one (the per-bin term is
/// convex and of degree one, so merging bins cannot raise it), which makes it a lower bound that
/// a few thousand coarse comparisons per millisecond evaluate, laid out bin by bin across views.
/// Only views whose bound is below the `total`-th distance of a first batch are compared in full.
class ViewIndex {
 public:
  explicit ViewIndex(const ViewDatabase& db);
  /// Each object's `per_object` nearest views, merged nearest first and cut to the nearest `total`
  /// (0: no cut); exactly nearest_views_per_object's answer when nothing is cut.
  std::vector<Match> nearest(const Vfh& query, std::size_t per_object, std::size_t total = 0) const;
  std::size_t views() const { return objects_.size(); }

 private:
  static constexpr std::size_t kGroup = 16;
  const ViewDatabase* db_;
  std::vector<std::uint32_t> objects_;  // per view
  std::vector<std::size_t> active_;     // coarse bins some view has mass in
  std::vector<float> coarse_;           // active_.size() x views, one row per coarse bin
};

}  // namespace viewpose
