#include "viewpose/database/matching.hpp"

#include <algorithm>
#include <limits>
#include <span>

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

namespace {

bool closer(const Match& a, const Match& b) { return a.distance < b.distance || (a.distance == b.distance && a.view < b.view); }

// Nearest first, at most `per_object` of each object, at most `total` in all (0: no cut).
std::vector<Match> capped(std::vector<Match> all, std::span<const std::uint32_t> object_of, std::size_t objects,
                          std::size_t per_object, std::size_t total) {
  std::sort(all.begin(), all.end(), closer);
  std::vector<std::size_t> taken(objects, 0);
  std::vector<Match> out;
  for (const Match& m : all) {
    if (total > 0 && out.size() >= total) break;
    if (taken[object_of[m.view]]++ < per_object) out.push_back(m);
  }
  return out;
}

}  // namespace

ViewIndex::ViewIndex(const ViewDatabase& db) : db_(&db) {
  const std::size_t n = db.views.size(), groups = (Vfh{}.size() + kGroup - 1) / kGroup;
  objects_.reserve(n);
  for (const ViewEntry& v : db.views) objects_.push_back(v.object);
  for (std::size_t g = 0; g < groups; ++g) {
    std::vector<float> row(n, 0.0f);
    bool any = false;
    for (std::size_t v = 0; v < n; ++v) {
      for (std::size_t b = g * kGroup; b < std::min(Vfh{}.size(), (g + 1) * kGroup); ++b) row[v] += db.views[v].vfh[b];
      any = any || row[v] != 0.0f;
    }
    if (!any) continue;  // no view has mass here: the query's own mass there is the same for all
    active_.push_back(g);
    coarse_.insert(coarse_.end(), row.begin(), row.end());
  }
}

std::vector<Match> ViewIndex::nearest(const Vfh& query, std::size_t per_object, std::size_t total) const {
  const std::size_t n = objects_.size();
  if (n == 0 || per_object == 0) return {};
  // Lower bounds: the coarse distance, summed bin by bin over all views (a loop that vectorizes).
  std::vector<float> bound(n, 0.0f);
  float constant = 0;  // the query's mass in coarse bins where every view is empty
  std::size_t next_active = 0;
  for (std::size_t g = 0; g * kGroup < query.size(); ++g) {
    float q = 0;
    for (std::size_t b = g * kGroup; b < std::min(query.size(), (g + 1) * kGroup); ++b) q += query[b];
    if (next_active == active_.size() || active_[next_active] != g) {
      constant += q;
      continue;
    }
    const float* row = coarse_.data() + next_active * n;
    ++next_active;
    for (std::size_t v = 0; v < n; ++v) {
      const float d = q - row[v], s = q + row[v];
      bound[v] += d * d / std::max(s, 1e-30f);  // s = 0 only where d = 0
    }
  }
  // A first batch, the views of smallest bound, compared in full: its cut distance is an upper
  // bound on the final one. Then every view whose bound is below it is compared in full too.
  const std::size_t batch = std::min(n, std::max<std::size_t>(4 * (total > 0 ? total : per_object), 64));
  std::vector<std::uint32_t> order(n);
  for (std::uint32_t v = 0; v < n; ++v) order[v] = v;
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(batch - 1), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return bound[a] < bound[b] || (bound[a] == bound[b] && a < b); });
  std::vector<char> done(n, 0);
  std::vector<Match> compared;
  for (std::size_t k = 0; k < batch; ++k) {
    compared.push_back({order[k], chi_squared(query, db_->views[order[k]].vfh)});
    done[order[k]] = 1;
  }
  const std::size_t objects = db_->objects.size();
  const std::vector<Match> first = capped(compared, objects_, objects, per_object, total);
  // Fewer than `total` found (few objects, or no cut): every view may still belong in.
  const bool full = total > 0 && first.size() >= total;
  const float cut = full ? first.back().distance : std::numeric_limits<float>::infinity();
  // The bound is summed in another order than the full distance: allow for rounding.
  const float slack = 1e-4f * cut + 1e-6f;
  for (std::uint32_t v = 0; v < n; ++v) {
    if (done[v] || bound[v] + constant > cut + slack) continue;
    compared.push_back({v, chi_squared(query, db_->views[v].vfh)});
  }
  return capped(std::move(compared), objects_, objects, per_object, total);
}

}  // namespace viewpose
