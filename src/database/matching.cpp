#include "viewpose/database/matching.hpp"

#include <algorithm>

namespace viewpose {

float chi_squared(const Vfh& a, const Vfh& b) {
  float sum = 0.0f;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const float s = a[i] + b[i];
    if (s > 0.0f) {
      const float d = a[i] - b[i];
      sum += d * d / s;
    }
  }
  return sum;
}

std::vector<Match> nearest_views(const ViewDatabase& db, const Vfh& query, std::size_t k) {
  std::vector<Match> all(db.views.size());
  for (std::size_t i = 0; i < db.views.size(); ++i) all[i] = {static_cast<std::uint32_t>(i), chi_squared(query, db.views[i].vfh)};
  const auto closer = [](const Match& a, const Match& b) { return a.distance < b.distance || (a.distance == b.distance && a.view < b.view); };
  k = std::min(k, all.size());
  std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(k), all.end(), closer);
  all.resize(k);
  return all;
}

std::vector<Match> nearest_views_per_object(const ViewDatabase& db, const Vfh& query, std::size_t k) {
  std::vector<std::vector<Match>> per_object(db.objects.size());
  for (std::size_t i = 0; i < db.views.size(); ++i) {
    per_object[db.views[i].object].push_back({static_cast<std::uint32_t>(i), chi_squared(query, db.views[i].vfh)});
  }
  const auto closer = [](const Match& a, const Match& b) { return a.distance < b.distance || (a.distance == b.distance && a.view < b.view); };
  std::vector<Match> out;
  for (auto& matches : per_object) {
    const std::size_t n = std::min(k, matches.size());
    std::partial_sort(matches.begin(), matches.begin() + static_cast<std::ptrdiff_t>(n), matches.end(), closer);
    out.insert(out.end(), matches.begin(), matches.begin() + static_cast<std::ptrdiff_t>(n));
  }
  std::sort(out.begin(), out.end(), closer);
  return out;
}

}  // namespace viewpose
