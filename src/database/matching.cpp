#include "viewpose/database/matching.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <tuple>

#include <Eigen/Eigenvalues>

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

ViewIndex::ViewIndex(const ViewDatabase& db, std::size_t candidates) : db_(&db), candidates_(candidates) {
  const std::size_t n = db.views.size();
  objects_.reserve(n);
  for (const ViewEntry& v : db.views) objects_.push_back(v.object);
  if (n <= candidates_) return;  // small: exhaustive and exact
  constexpr Eigen::Index kBins = std::tuple_size_v<Vfh>;
  const auto root = [](const Vfh& h) {
    Eigen::Matrix<float, kBins, 1> r;
    for (Eigen::Index b = 0; b < kBins; ++b) r[b] = std::sqrt(std::max(0.0f, h[static_cast<std::size_t>(b)]));
    return r;
  };
  // Principal directions from an even sample of at most 4000 views.
  const std::size_t sample = std::min<std::size_t>(n, 4000);
  Eigen::MatrixXd X(kBins, static_cast<Eigen::Index>(sample));
  for (std::size_t k = 0; k < sample; ++k) X.col(static_cast<Eigen::Index>(k)) = root(db.views[k * n / sample].vfh).cast<double>();
  const Eigen::VectorXd mean = X.rowwise().mean();
  X.colwise() -= mean;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(X * X.transpose());
  directions_ = eig.eigenvectors().rightCols(kDirections).transpose().cast<float>();  // largest eigenvalues last
  mean_ = mean.cast<float>();
  coordinates_.resize(static_cast<std::size_t>(kDirections) * n);
  for (std::size_t v = 0; v < n; ++v) {
    Eigen::Map<Eigen::Matrix<float, kDirections, 1>>(coordinates_.data() + v * kDirections) = directions_ * (root(db.views[v].vfh) - mean_);
  }
}

std::vector<Match> ViewIndex::nearest(const Vfh& query, std::size_t per_object, std::size_t total) const {
  const std::size_t n = objects_.size();
  if (n == 0 || per_object == 0) return {};
  std::vector<Match> compared;
  if (exhaustive()) {
    for (std::uint32_t v = 0; v < n; ++v) compared.push_back({v, chi_squared(query, db_->views[v].vfh)});
    return capped(std::move(compared), objects_, db_->objects.size(), per_object, total);
  }
  Eigen::Matrix<float, Eigen::Dynamic, 1> r(mean_.size());
  for (Eigen::Index b = 0; b < r.size(); ++b) r[b] = std::sqrt(std::max(0.0f, query[static_cast<std::size_t>(b)]));
  const Eigen::Matrix<float, kDirections, 1> q = directions_ * (r - mean_);
  std::vector<float> near(n);
  const auto views = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static) if (n > 20000)
  for (std::ptrdiff_t v = 0; v < views; ++v) {
    const auto coordinates = Eigen::Map<const Eigen::Matrix<float, kDirections, 1>>(coordinates_.data() + static_cast<std::size_t>(v) * kDirections);
    near[static_cast<std::size_t>(v)] = (coordinates - q).squaredNorm();
  }
  // The `keep` nearest: the keep-th smallest distance found on a copy, then the views below it (and
  // as many at it as fill the count), in view order.
  const std::size_t keep = std::min(n, std::max(candidates_, 2 * std::max(total, per_object)));
  std::vector<float> order = near;
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep - 1), order.end());
  const float cut = order[keep - 1];
  std::vector<std::uint32_t> chosen;
  chosen.reserve(keep);
  for (std::uint32_t v = 0; v < n; ++v) {
    if (near[v] < cut) chosen.push_back(v);
  }
  for (std::uint32_t v = 0; v < n && chosen.size() < keep; ++v) {
    if (near[v] == cut) chosen.push_back(v);
  }
  compared.resize(chosen.size());
#pragma omp parallel for schedule(static) if (chosen.size() > 500)
  for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(chosen.size()); ++k) {
    const std::uint32_t v = chosen[static_cast<std::size_t>(k)];
    compared[static_cast<std::size_t>(k)] = {v, chi_squared(query, db_->views[v].vfh)};
  }
  return capped(std::move(compared), objects_, db_->objects.size(), per_object, total);
}

}  // namespace viewpose
