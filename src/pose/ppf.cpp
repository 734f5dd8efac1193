#include "viewpose/pose/ppf.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <Eigen/Geometry>

#include "viewpose/core/error.hpp"
#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/threads.hpp"

namespace viewpose {

namespace {

constexpr double kPi = 3.14159265358979323846;

// The rigid motion that takes `p` to the origin and its normal `n` onto +x.
Transform local_frame(const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  const Eigen::Matrix3d R = Eigen::Quaterniond::FromTwoVectors(n.cast<double>(), Eigen::Vector3d::UnitX()).toRotationMatrix();
  return make_transform(R, -R * p.cast<double>());
}

// The second point's angle about +x in the first point's local frame.
float pair_alpha(const Transform& T_local, const Eigen::Vector3f& p2) {
  const Eigen::Vector3d q = T_local * p2.cast<double>();
  return static_cast<float>(std::atan2(q.z(), q.y()));
}

// Angles about the normal in fine units: a whole number of them in every alpha bin, so that a
// vote's bin is integer arithmetic (most of the time goes to votes).
constexpr std::uint32_t kAlphaUnits = PpfTable::kAlphaUnits;
std::uint32_t alpha_units(float alpha) {
  double a = alpha < 0 ? alpha + 2 * kPi : alpha;
  return std::min(kAlphaUnits - 1, static_cast<std::uint32_t>(a / (2 * kPi) * kAlphaUnits));
}

struct Feature {
  float distance = 0, a1 = 0, a2 = 0, a3 = 0;
};

// F(p1, p2); false for coincident points.
bool pair_feature(const Eigen::Vector3f& p1, const Eigen::Vector3f& n1, const Eigen::Vector3f& p2, const Eigen::Vector3f& n2,
                  Feature& f) {
  const Eigen::Vector3f d = p2 - p1;
  f.distance = d.norm();
  if (!(f.distance > 1e-6f)) return false;
  const Eigen::Vector3f u = d / f.distance;
  const auto angle = [](float c) { return std::acos(std::clamp(c, -1.0f, 1.0f)); };
  f.a1 = angle(n1.dot(u));
  f.a2 = angle(n2.dot(u));
  f.a3 = angle(n1.dot(n2));
  return true;
}

// The bin of x (in steps), and the neighbouring one when x lies within `spread` of its edge: up to
// two bins, the own first. Returns how many.
int bins_of(float x_in_steps, int bins, double spread, int out[2]) {
  const int b = std::clamp(static_cast<int>(std::floor(x_in_steps)), 0, bins - 1);
  out[0] = b;
  if (spread <= 0) return 1;
  const double frac = x_in_steps - b;
  if (frac < spread && b > 0) return out[1] = b - 1, 2;
  if (frac > 1.0 - spread && b < bins - 1) return out[1] = b + 1, 2;
  return 1;
}

// The table's layout: distance bins of one sampling step up to the diameter, and angle bins of
// 2 pi / angle_bins over [0, pi].
int distance_bins_of(double sample_fraction) { return static_cast<int>(std::floor(1.0 / sample_fraction)) + 1; }
int feature_angle_bins_of(int angle_bins) { return static_cast<int>(std::ceil(angle_bins / 2.0 - 1e-9)); }
std::size_t key_of(int feature_angle_bins, int d, int a1, int a2, int a3) {
  const auto A = static_cast<std::size_t>(feature_angle_bins);
  return ((static_cast<std::size_t>(d) * A + static_cast<std::size_t>(a1)) * A + static_cast<std::size_t>(a2)) * A +
         static_cast<std::size_t>(a3);
}
std::size_t keys_of(double sample_fraction, int angle_bins) {
  const int A = feature_angle_bins_of(angle_bins);
  return key_of(A, distance_bins_of(sample_fraction) - 1, A - 1, A - 1, A - 1) + 1;
}

}  // namespace

OrientedPoints ppf_sample(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, float step_m,
                          double normal_split_deg) {
  if (points.size() != normals.size()) throw Error("ppf: points and normals differ in number");
  if (!(step_m > 0)) throw Error("ppf: the sampling step must be positive");
  struct Keyed {
    std::int64_t x, y, z;
    std::uint32_t index;
  };
  std::vector<Keyed> keyed;
  keyed.reserve(points.size());
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite() || !normals[i].allFinite() || normals[i].squaredNorm() < 0.25f) continue;
    keyed.push_back({static_cast<std::int64_t>(std::floor(points[i].x() / step_m)),
                     static_cast<std::int64_t>(std::floor(points[i].y() / step_m)),
                     static_cast<std::int64_t>(std::floor(points[i].z() / step_m)), i});
  }
  std::sort(keyed.begin(), keyed.end(), [](const Keyed& a, const Keyed& b) {
    return std::tie(a.x, a.y, a.z, a.index) < std::tie(b.x, b.y, b.z, b.index);
  });
  const float cos_split = static_cast<float>(std::cos(normal_split_deg * kPi / 180.0));
  OrientedPoints out;
  struct Group {
    Eigen::Vector3f sum_p = Eigen::Vector3f::Zero(), sum_n = Eigen::Vector3f::Zero(), first_n = Eigen::Vector3f::Zero();
    int count = 0;
  };
  std::vector<Group> groups;
  for (std::size_t begin = 0; begin < keyed.size();) {
    std::size_t end = begin;
    while (end < keyed.size() && keyed[end].x == keyed[begin].x && keyed[end].y == keyed[begin].y && keyed[end].z == keyed[begin].z) ++end;
    groups.clear();
    for (std::size_t k = begin; k < end; ++k) {
      const Eigen::Vector3f n = normals[keyed[k].index].normalized();
      Group* g = nullptr;
      for (Group& candidate : groups) {
        if (candidate.first_n.dot(n) >= cos_split) {
          g = &candidate;
          break;
        }
      }
      if (!g) {
        Group fresh;
        fresh.first_n = n;
        groups.push_back(fresh);
        g = &groups.back();
      }
      g->sum_p += points[keyed[k].index];
      g->sum_n += n;
      ++g->count;
    }
    for (const Group& g : groups) {
      if (g.sum_n.squaredNorm() < 1e-12f) continue;
      out.points.push_back(g.sum_p / static_cast<float>(g.count));
      out.normals.push_back(g.sum_n.normalized());
    }
    begin = end;
  }
  return out;
}

std::size_t PpfModel::key(int d, int a1, int a2, int a3) const { return key_of(feature_angle_bins_, d, a1, a2, a3); }

void check_ppf_options(const PpfOptions& options) {
  // (The table's keys, 4 bytes each, at most 2^24: 1/sample_fraction distance bins times (angle_bins / 2)^3.)
  if (!(options.sample_fraction >= 1e-3 && options.sample_fraction < 1) || options.angle_bins < 4 ||
      kAlphaUnits % static_cast<std::uint32_t>(options.angle_bins) != 0 || options.reference_stride < 1 ||
      keys_of(options.sample_fraction, options.angle_bins) > (std::size_t{1} << 24)) {
    throw Error("ppf: bad options (sample_fraction in [0.001, 1), angle_bins >= 4 dividing 13440, at most 2^24 feature bins, "
                "reference_stride >= 1)");
  }
}

std::size_t PpfTable::bytes() const {
  return sampled.size() * 2 * sizeof(Eigen::Vector3f) + (key_start.size() + entries.size()) * sizeof(std::uint32_t);
}

bool PpfTable::made_with(const PpfOptions& options) const {
  return sample_fraction == options.sample_fraction && angle_bins == options.angle_bins &&
         normal_split_deg == options.normal_split_deg;
}

PpfTable make_ppf_table(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, double diameter_m,
                        const PpfOptions& options) {
  if (!(diameter_m > 0) || !std::isfinite(diameter_m)) throw Error("ppf: the object's diameter must be positive");
  check_ppf_options(options);
  PpfTable t;
  t.diameter_m = diameter_m;
  t.sample_fraction = options.sample_fraction;
  t.angle_bins = options.angle_bins;
  t.normal_split_deg = options.normal_split_deg;
  const auto step_m = static_cast<float>(options.sample_fraction * diameter_m);
  const int distance_bins = distance_bins_of(options.sample_fraction);
  const int feature_angle_bins = feature_angle_bins_of(options.angle_bins);
  const double angle_step = 2 * kPi / options.angle_bins;
  t.sampled = ppf_sample(points, normals, step_m, options.normal_split_deg);
  const std::size_t n = t.sampled.size();
  if (n < 2) throw Error("ppf: the model has fewer than two oriented points");
  if (n > PpfTable::kMaxPoints) throw Error("ppf: the model samples to too many points for a pair table (raise sample_fraction)");

  // Every ordered pair within the diameter, keyed: each first point's pairs on a thread, then all in
  // the order of their first points (the same table whatever the threads), counted, then placed.
  struct Pairs {
    std::vector<std::uint32_t> keys, entries;
  };
  std::vector<Pairs> by_point(n);
  const float max_d = static_cast<float>(diameter_m);
  FirstException failed;
#pragma omp parallel for schedule(dynamic, 16)
  for (std::ptrdiff_t pi = 0; pi < static_cast<std::ptrdiff_t>(n); ++pi) {
    failed.run(pi, [&] {
      const auto i = static_cast<std::size_t>(pi);
      Pairs& out = by_point[i];
      const Transform T_local_model = local_frame(t.sampled.points[i], t.sampled.normals[i]);
      for (std::size_t j = 0; j < n; ++j) {
        Feature f;
        if (i == j || !pair_feature(t.sampled.points[i], t.sampled.normals[i], t.sampled.points[j], t.sampled.normals[j], f) ||
            f.distance > max_d) {
          continue;
        }
        const int d = std::min(distance_bins - 1, static_cast<int>(f.distance / step_m));
        const auto a = [&](float x) { return std::min(feature_angle_bins - 1, static_cast<int>(x / angle_step)); };
        out.keys.push_back(static_cast<std::uint32_t>(key_of(feature_angle_bins, d, a(f.a1), a(f.a2), a(f.a3))));
        out.entries.push_back(PpfTable::entry(static_cast<std::uint32_t>(i), alpha_units(pair_alpha(T_local_model, t.sampled.points[j]))));
      }
    });
  }
  failed.rethrow();
  std::size_t pairs = 0;
  for (const Pairs& p : by_point) pairs += p.keys.size();
  if (pairs >= std::numeric_limits<std::uint32_t>::max()) {
    throw Error("ppf: the model has too many pairs for a pair table (raise sample_fraction)");
  }
  std::vector<std::uint32_t> pair_key, pair_entry;
  pair_key.reserve(pairs);
  pair_entry.reserve(pairs);
  for (Pairs& p : by_point) {
    pair_key.insert(pair_key.end(), p.keys.begin(), p.keys.end());
    pair_entry.insert(pair_entry.end(), p.entries.begin(), p.entries.end());
    p = Pairs{};
  }
  t.key_start.assign(keys_of(options.sample_fraction, options.angle_bins) + 1, 0);
  for (const std::uint32_t k : pair_key) ++t.key_start[k + 1];
  std::partial_sum(t.key_start.begin(), t.key_start.end(), t.key_start.begin());
  t.entries.resize(pair_entry.size());
  std::vector<std::uint32_t> fill(t.key_start.begin(), t.key_start.end() - 1);
  for (std::size_t p = 0; p < pair_entry.size(); ++p) t.entries[fill[pair_key[p]]++] = pair_entry[p];
  return t;
}

void check_ppf_table(const PpfTable& t) {
  const auto fail = [](const char* why) { throw Error(std::string("ppf: a pair table ") + why); };
  if (!(t.diameter_m > 0) || !std::isfinite(t.diameter_m)) fail("has no positive diameter");
  PpfOptions shape;
  shape.sample_fraction = t.sample_fraction;
  shape.angle_bins = t.angle_bins;
  if (!(t.sample_fraction >= 1e-3) || !std::isfinite(t.normal_split_deg)) fail("has bad options");
  try {
    check_ppf_options(shape);
  } catch (const Error&) {
    fail("has bad options");
  }
  const std::size_t n = t.sampled.size();
  if (t.sampled.normals.size() != n || n < 2 || n > PpfTable::kMaxPoints) fail("has a bad number of points or normals");
  for (std::size_t i = 0; i < n; ++i) {
    if (!t.sampled.points[i].allFinite() || !(std::abs(t.sampled.normals[i].norm() - 1.0f) < 1e-3f)) fail("has a point or normal that is not finite or not unit");
  }
  if (t.key_start.size() != keys_of(t.sample_fraction, t.angle_bins) + 1 || t.key_start.front() != 0 ||
      t.key_start.back() != t.entries.size()) {
    fail("has keys that do not match its options or its pairs");
  }
  if (!std::is_sorted(t.key_start.begin(), t.key_start.end())) fail("has keys out of order");
  const auto points = static_cast<std::uint32_t>(n);
  constexpr std::uint32_t alpha_mask = (std::uint32_t{1} << PpfTable::kAlphaBits) - 1;
  for (const std::uint32_t e : t.entries) {
    if ((e >> PpfTable::kAlphaBits) >= points) fail("has a pair naming a point that does not exist");
    if ((e & alpha_mask) >= kAlphaUnits) fail("has a pair whose angle is out of range");
  }
}

PpfModel::PpfModel(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, double diameter_m,
                   const PpfOptions& options)
    : table_(std::make_shared<const PpfTable>(make_ppf_table(points, normals, diameter_m, options))), options_(options) {
  prepare();
}

PpfModel::PpfModel(std::shared_ptr<const PpfTable> table, const PpfOptions& options) : table_(std::move(table)), options_(options) {
  if (!table_) throw Error("ppf: no pair table given");
  check_ppf_table(*table_);
  check_ppf_options(options);
  prepare();
}

void PpfModel::prepare() {
  const PpfTable& t = *table_;
  // The table's shape holds where the options differ from it.
  options_.sample_fraction = t.sample_fraction;
  options_.angle_bins = t.angle_bins;
  options_.normal_split_deg = t.normal_split_deg;
  step_m_ = static_cast<float>(t.sample_fraction * t.diameter_m);
  distance_bins_ = distance_bins_of(t.sample_fraction);
  feature_angle_bins_ = feature_angle_bins_of(t.angle_bins);
  phi_bin_.resize(2 * kAlphaUnits);
  for (std::uint32_t x = 0; x < 2 * kAlphaUnits; ++x) {
    phi_bin_[x] = static_cast<std::uint16_t>((x % kAlphaUnits) / (kAlphaUnits / static_cast<std::uint32_t>(t.angle_bins)));
  }
  T_local_model_.resize(t.sampled.size());
  for (std::size_t i = 0; i < t.sampled.size(); ++i) T_local_model_[i] = local_frame(t.sampled.points[i], t.sampled.normals[i]);
}

std::vector<PpfHypothesis> PpfModel::hypotheses(const OrientedPoints& scene) const {
  std::vector<PpfHypothesis> out;
  if (scene.size() < 2) return out;
  const int bins = options_.angle_bins;
  const double angle_step = 2 * kPi / bins;
  const KdTree tree(scene.points);
  // Every reference_stride-th sampled point, and no more than max_reference_points of them, spread
  // over the whole region (the sample is in grid order): a region's votes take a bounded time.
  auto stride = static_cast<std::size_t>(options_.reference_stride);
  if (options_.max_reference_points > 0) {
    stride = std::max(stride, (scene.size() + options_.max_reference_points - 1) / options_.max_reference_points);
  }
  const std::size_t references = (scene.size() + stride - 1) / stride;
  struct Peak {
    Transform T_camera_object = Transform::Identity();
    std::uint32_t votes = 0;
  };
  std::vector<Peak> peaks(references);
  const PpfTable& table = *table_;
  const float radius = static_cast<float>(table.diameter_m);
  const std::size_t model_points = table.sampled.size();
  const auto max_bucket = static_cast<std::uint32_t>(std::max(1.0, options_.max_bucket_per_point * static_cast<double>(model_points)));
  const std::uint32_t* key_start = table.key_start.data();
  const std::uint32_t* entries = table.entries.data();
  constexpr std::uint32_t alpha_mask = (std::uint32_t{1} << PpfTable::kAlphaBits) - 1;

  FirstException failed;
#pragma omp parallel
  {
    std::vector<std::uint32_t> votes, touched, neighbours;
    // (A thread that cannot have its buffers runs no iteration: as index -1, below every
    // iteration's, its failure makes failed.run skip them all.)
    failed.run(-1, [&] {
      votes.assign(model_points * static_cast<std::size_t>(bins), 0);
      // The slots voted for, each once: written on every vote and counted on a slot's first, without
      // a branch the processor would mispredict half the time (one more, for the write after all).
      touched.resize(votes.size() + 1);
    });
    std::size_t n_touched = 0;
#pragma omp for schedule(dynamic, 16)
    for (std::ptrdiff_t r = 0; r < static_cast<std::ptrdiff_t>(references); ++r) {
      failed.run(r, [&] {
        const std::size_t s1 = static_cast<std::size_t>(r) * stride;
        const Eigen::Vector3f& p1 = scene.points[s1];
        const Eigen::Vector3f& n1 = scene.normals[s1];
        const Transform T_local_scene = local_frame(p1, n1);
        tree.radius_search(p1, radius, neighbours);
        // The peak: the model point and angle most pairs agree on (of equals, the lowest slot).
        std::uint32_t best = 0, best_slot = 0;
        for (const std::uint32_t s2 : neighbours) {
          Feature f;
          if (s2 == s1 || !pair_feature(p1, n1, scene.points[s2], scene.normals[s2], f)) continue;
          const std::uint32_t alpha_scene_fine = alpha_units(pair_alpha(T_local_scene, scene.points[s2]));
          int d[2], a1[2], a2[2], a3[2];
          const double spread = options_.spread_fraction;
          const int nd = bins_of(f.distance / step_m_, distance_bins_, spread, d);
          const int n1b = bins_of(static_cast<float>(f.a1 / angle_step), feature_angle_bins_, spread, a1);
          const int n2b = bins_of(static_cast<float>(f.a2 / angle_step), feature_angle_bins_, spread, a2);
          const int n3b = bins_of(static_cast<float>(f.a3 / angle_step), feature_angle_bins_, spread, a3);
          for (int i = 0; i < nd; ++i)
            for (int j = 0; j < n1b; ++j)
              for (int k = 0; k < n2b; ++k)
                for (int l = 0; l < n3b; ++l) {
                  const std::size_t kk = key(d[i], a1[j], a2[k], a3[l]);
                  if (key_start[kk + 1] - key_start[kk] > max_bucket) continue;
                  for (std::uint32_t e = key_start[kk]; e < key_start[kk + 1]; ++e) {
                    const std::uint32_t point = entries[e] >> PpfTable::kAlphaBits, alpha = entries[e] & alpha_mask;
                    // phi = alpha_scene - alpha_model in fine units, wrapped into [0, 2 pi), and its bin.
                    const std::size_t slot = point * static_cast<std::size_t>(bins) + phi_bin_[alpha_scene_fine + kAlphaUnits - alpha];
                    const std::uint32_t v = ++votes[slot];
                    touched[n_touched] = static_cast<std::uint32_t>(slot);
                    n_touched += v == 1;
                    if (v > best || (v == best && slot < best_slot)) best = v, best_slot = static_cast<std::uint32_t>(slot);
                  }
                }
        }
        for (std::size_t i = 0; i < n_touched; ++i) votes[touched[i]] = 0;
        n_touched = 0;
        if (best == 0) return;
        const std::uint32_t m = best_slot / static_cast<std::uint32_t>(bins);
        const double phi = (static_cast<double>(best_slot % static_cast<std::uint32_t>(bins)) + 0.5) * angle_step;
        const Transform Rx = make_transform(Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitX()).toRotationMatrix(), Eigen::Vector3d::Zero());
        peaks[static_cast<std::size_t>(r)] = {T_local_scene.inverse() * Rx * T_local_model_[m], best};
      });
    }
  }
  failed.rethrow();

  // Poses clustered, most votes first: each joins the first cluster (most votes) it is near.
  std::vector<std::size_t> order(peaks.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return peaks[a].votes > peaks[b].votes; });
  struct PoseCluster {
    Transform first;
    Eigen::Vector3d sum_t = Eigen::Vector3d::Zero();
    Eigen::Vector4d sum_q = Eigen::Vector4d::Zero();
    double votes = 0;
    std::size_t poses = 0;
  };
  std::vector<PoseCluster> clusters;
  const double max_t = options_.cluster_distance_fraction * table.diameter_m;
  const double max_angle = options_.cluster_angle_deg * kPi / 180.0;
  for (const std::size_t i : order) {
    const Peak& p = peaks[i];
    if (p.votes == 0) break;
    PoseCluster* home = nullptr;
    for (PoseCluster& c : clusters) {
      if ((c.first.translation() - p.T_camera_object.translation()).norm() > max_t) continue;
      const Eigen::AngleAxisd diff(c.first.linear().transpose() * p.T_camera_object.linear());
      if (std::abs(diff.angle()) > max_angle) continue;
      home = &c;
      break;
    }
    if (!home) {
      clusters.push_back({p.T_camera_object});
      home = &clusters.back();
    }
    Eigen::Quaterniond q(p.T_camera_object.linear());
    const Eigen::Quaterniond q0(home->first.linear());
    if (q.dot(q0) < 0) q.coeffs() = -q.coeffs();
    home->sum_t += p.votes * p.T_camera_object.translation();
    home->sum_q += p.votes * q.coeffs();
    home->votes += p.votes;
    ++home->poses;
  }
  std::stable_sort(clusters.begin(), clusters.end(), [](const PoseCluster& a, const PoseCluster& b) { return a.votes > b.votes; });
  for (const PoseCluster& c : clusters) {
    if (out.size() >= options_.max_hypotheses) break;
    Eigen::Quaterniond q;
    q.coeffs() = c.sum_q.normalized();
    out.push_back({make_transform(q.toRotationMatrix(), c.sum_t / c.votes), c.votes, c.poses});
  }
  return out;
}

}  // namespace viewpose
