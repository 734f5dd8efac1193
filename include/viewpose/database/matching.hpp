#pragma once
// Matching a description against the database: the k views nearest by chi-squared distance, by
// exhaustive search (exact).
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

}  // namespace viewpose
