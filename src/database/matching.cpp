#include "viewpose/database/matching.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <tuple>

#include <Eigen/Eigenvalues>

#include "viewpose/core/threads.hpp"

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
  // Small: exhaustive and exact. Up to twice `candidates` views a full search costs little more
  // than the index's own pass and its candidates (640 views: 0.19 against 0.13 ms a query), and
  // the principal directions are not found at start-up (13-27 ms).
  if (n <= 2 * candidates_) return;
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
  std::vector<float> coordinates(static_cast<std::size_t>(kDirections) * n);
  for (std::size_t v = 0; v < n; ++v) {
    Eigen::Map<Eigen::Matrix<float, kDirections, 1>>(coordinates.data() + v * kDirections) = directions_ * (root(db.views[v].vfh) - mean_);
  }
  // Kept as one byte per direction, each direction scaled to its own range: a quarter of the
  // memory to read per query (1.3 MB for 80,000 views), which matters more than the rounding
  // (half a step in 255) for a pre-selection that is compared in full afterwards.
  for (int d = 0; d < kDirections; ++d) {
    float largest = 0;
    for (std::size_t v = 0; v < n; ++v) largest = std::max(largest, std::abs(coordinates[v * kDirections + static_cast<std::size_t>(d)]));
    step_[d] = largest > 0 ? largest / 127.0f : 1.0f;
  }
  coordinates_.resize(coordinates.size());
  for (std::size_t k = 0; k < coordinates.size(); ++k) {
    coordinates_[k] = static_cast<std::int8_t>(std::lround(std::clamp(coordinates[k] / step_[k % kDirections], -127.0f, 127.0f)));
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
  // The query in steps, and each direction's squared step as its weight.
  float q_steps[kDirections], weight[kDirections];
  for (int d = 0; d < kDirections; ++d) q_steps[d] = q[d] / step_[d], weight[d] = step_[d] * step_[d];
  // The `keep` views nearest in these coordinates (ties to the lower view index): each thread keeps
  // the best of its share in a bounded heap, as the distances are computed, which most views leave
  // at one comparison with the heap's top; then the shares are merged.
  const std::size_t keep = std::min(n, std::max(candidates_, 2 * std::max(total, per_object)));
  using Near = std::pair<float, std::uint32_t>;  // (distance, view): ordered as the ties need
  const int shares = n > 20000 ? std::max(1, thread_count()) : 1;
  std::vector<std::vector<Near>> heaps(static_cast<std::size_t>(shares));
  FirstException failed;
#pragma omp parallel for schedule(static, 1) num_threads(shares) if (shares > 1)
  for (int share = 0; share < shares; ++share) {
    failed.run(share, [&] {
      std::vector<Near>& heap = heaps[static_cast<std::size_t>(share)];
      heap.reserve(keep + 1);
      const std::size_t begin = n * static_cast<std::size_t>(share) / static_cast<std::size_t>(shares),
                        end = n * static_cast<std::size_t>(share + 1) / static_cast<std::size_t>(shares);
      for (std::size_t v = begin; v < end; ++v) {
        const std::int8_t* c = coordinates_.data() + v * kDirections;
        float sum = 0;
        for (int d = 0; d < kDirections; ++d) {
          const float diff = static_cast<float>(c[d]) - q_steps[d];
          sum += weight[d] * diff * diff;
        }
        const Near item{sum, static_cast<std::uint32_t>(v)};
        if (heap.size() < keep) {
          heap.push_back(item);
          std::push_heap(heap.begin(), heap.end());
        } else if (item < heap.front()) {
          std::pop_heap(heap.begin(), heap.end());
          heap.back() = item;
          std::push_heap(heap.begin(), heap.end());
        }
      }
    });
  }
  failed.rethrow();
  std::vector<Near> merged;
  for (const auto& heap : heaps) merged.insert(merged.end(), heap.begin(), heap.end());
  std::sort(merged.begin(), merged.end());
  merged.resize(std::min(keep, merged.size()));
  std::vector<std::uint32_t> chosen;
  chosen.reserve(merged.size());
  for (const Near& m : merged) chosen.push_back(m.second);
  compared.resize(chosen.size());
  // In full, on all threads: the candidates' histograms lie anywhere in a large database, and each
  // is read from memory rather than cache.
#pragma omp parallel for schedule(static) if (chosen.size() >= 200)
  for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(chosen.size()); ++k) {
    const std::uint32_t v = chosen[static_cast<std::size_t>(k)];
    compared[static_cast<std::size_t>(k)] = {v, chi_squared(query, db_->views[v].vfh)};
  }
  return capped(std::move(compared), objects_, db_->objects.size(), per_object, total);
}

}  // namespace viewpose
