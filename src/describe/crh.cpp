#include "viewpose/describe/crh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <utility>

#include <Eigen/Geometry>

#include "core/clones.hpp"

namespace viewpose {

namespace {
constexpr int kBins = 90;
constexpr double kPi = std::numbers::pi;

// The harmonics a CRH spectrum holds, by row: 0 to 44, then the Nyquist term at 89.
constexpr int harmonic(int row) { return row < kBins / 2 ? row : kBins - 1; }

// The spectra are zero-padded to 2 kBins lags (2-degree steps); the inverse transform is summed
// over the first half of them.
constexpr int kLags = 2 * kBins;
constexpr int kHalf = kLags / 2;

// One harmonic's share of the inverse transform's real part at each of the first half of the
// lags: sum[n] += p_re cos[n] - p_im sin[n]. Half a roll search's time; compiled for AVX2 too
// (4 lags at once, where any x86-64 does 2), each lag's sum the same in either (this file is
// compiled without fused multiply-adds, src/CMakeLists.txt).
VIEWPOSE_CLONES void add_harmonic(double* sum, const double* cos, const double* sin, double p_re, double p_im) {
  for (int n = 0; n < kHalf; ++n) sum[n] += p_re * cos[n] - p_im * sin[n];
}

// PCL's rotation taking the ray through `centroid` to the z axis, built as CRHEstimation builds it.
template <typename Scalar>
Eigen::Matrix<Scalar, 3, 3> ray_rotation(const Eigen::Matrix<Scalar, 3, 1>& centroid) {
  Eigen::Matrix<Scalar, 3, 1> plane_normal = -centroid;
  plane_normal.normalize();
  Eigen::Matrix<Scalar, 3, 1> axis = plane_normal.cross(Eigen::Matrix<Scalar, 3, 1>::UnitZ());
  const double rotation = -std::asin(std::min<double>(1.0, axis.norm()));
  axis.normalize();
  return Eigen::AngleAxis<Scalar>(static_cast<Scalar>(rotation), axis).toRotationMatrix();
}
}  // namespace

Eigen::Matrix3d ray_to_z(const Eigen::Vector3d& centroid) { return ray_rotation<double>(centroid); }

Crh compute_crh(std::span<const Eigen::Vector3f> normals, const Eigen::Vector3f& centroid) {
  const Eigen::Matrix3f R = ray_rotation<float>(centroid);
  std::array<float, kBins> spatial{};
  float sum_w = 0.0f;
  for (const Eigen::Vector3f& normal : normals) {
    if (!normal.allFinite()) continue;
    const Eigen::Vector3f n = R * normal;
    const int bin = static_cast<int>(((std::atan2(n.y(), n.x()) + kPi) * 180.0 / kPi) / (360 / kBins)) % kBins;
    const float w = std::sqrt(n.y() * n.y() + n.x() * n.x());
    sum_w += w;
    spatial[static_cast<std::size_t>(bin)] += w;
  }
  Crh crh{};
  if (!(sum_w > 0)) return crh;
  for (float& s : spatial) s /= sum_w;
  // Real DFT, harmonics 0..45, each divided by the constant term (which is 1 after the division).
  std::array<std::complex<double>, kBins / 2 + 1> F;
  for (int k = 0; k <= kBins / 2; ++k) {
    std::complex<double> sum = 0;
    for (int j = 0; j < kBins; ++j) sum += static_cast<double>(spatial[static_cast<std::size_t>(j)]) * std::polar(1.0, -2 * kPi * k * j / kBins);
    F[static_cast<std::size_t>(k)] = sum;
  }
  const double f0 = F[0].real();
  crh[0] = static_cast<float>(F[0].real() / f0);
  for (int k = 1; k < kBins / 2; ++k) {
    crh[static_cast<std::size_t>(2 * k - 1)] = static_cast<float>(F[static_cast<std::size_t>(k)].real() / f0);
    crh[static_cast<std::size_t>(2 * k)] = static_cast<float>(F[static_cast<std::size_t>(k)].imag() / f0);
  }
  crh[kBins - 1] = static_cast<float>(F[kBins / 2].real() / f0);
  return crh;
}

std::vector<float> crh_roll_angles(const Crh& view, const Crh& scene, const RollOptions& options) {
  // Phase correlation: conj(view) * scene, each harmonic scaled to unit magnitude. Like PCL, the
  // Nyquist product lands at index 89 of the padded spectrum.
  std::array<std::complex<double>, kLags> product{};
  product[0] = static_cast<double>(view[0]) * scene[0];
  for (int k = 1; k < kBins / 2; ++k) {
    const std::complex<float> a(view[static_cast<std::size_t>(2 * k - 1)], -view[static_cast<std::size_t>(2 * k)]);
    const std::complex<float> b(scene[static_cast<std::size_t>(2 * k - 1)], scene[static_cast<std::size_t>(2 * k)]);
    const std::complex<float> ab = a * b;
    // |ab| as glibc's hypotf computes it (in double, rounded once), without the call (the test
    // against std::abs holds it to that, with glibc).
    const float magnitude = static_cast<float>(std::sqrt(static_cast<double>(ab.real()) * ab.real() + static_cast<double>(ab.imag()) * ab.imag()));
    product[static_cast<std::size_t>(k)] = magnitude > 0 ? std::complex<double>(ab / magnitude) : 0.0;
  }
  product[kBins - 1] = static_cast<double>(view[kBins - 1]) * scene[kBins - 1];
  // The inverse transform's real part at each lag. Only the harmonics present (0 to 44 and the
  // Nyquist term at 89, 46 of 180) take part: the sum over the others adds zeros. Each present
  // harmonic adds p.re cos - p.im sin (the real part of p * root, as std::complex computes it,
  // without its checks for infinities) to every lag, from a table of its roots row by row, read
  // in a stream the compiler vectorizes (a table of the 180 roots indexed by k n mod 180 read six
  // times slower). Half a turn on, a harmonic's root is the same times (-1)^k: the even
  // harmonics' sum E and the odd ones' O over the first 90 lags give all 180, E + O and E - O,
  // for half the products. (Each of E and O adds its harmonics in order; the test holds the
  // angles to the textbook sum's.)
  constexpr int kHarmonics = kBins / 2 + 1;
  struct Table {
    std::array<std::array<double, kHalf>, kHarmonics> cos{}, sin{};
  };
  static const Table table = [] {
    Table t;
    for (int row = 0; row < kHarmonics; ++row)
      for (int n = 0; n < kHalf; ++n) {
        const std::complex<double> root = std::polar(1.0, 2 * kPi * ((harmonic(row) * n) % kLags) / kLags);
        t.cos[static_cast<std::size_t>(row)][static_cast<std::size_t>(n)] = root.real();
        t.sin[static_cast<std::size_t>(row)][static_cast<std::size_t>(n)] = root.imag();
      }
    return t;
  }();
  std::array<double, kHalf> even{}, odd{};
  for (int row = 0; row < kHarmonics; ++row) {
    const std::complex<double>& p = product[static_cast<std::size_t>(harmonic(row))];
    if (p == 0.0) continue;
    std::array<double, kHalf>& sum = harmonic(row) % 2 == 0 ? even : odd;
    add_harmonic(sum.data(), table.cos[static_cast<std::size_t>(row)].data(), table.sin[static_cast<std::size_t>(row)].data(), p.real(), p.imag());
  }
  std::array<double, kLags> re{};
  for (std::size_t n = 0; n < kHalf; ++n) re[n] = even[n] + odd[n], re[n + kHalf] = even[n] - odd[n];
  // The lags best first, as a stable sort by value would order them (ties: the smaller lag first);
  // of the first `scan`, those below accept_threshold times the best are passed over. So only the
  // lags at or above that bar are ordered (on random spectra, 17 of the 180 at half the best, 4 at
  // 0.8 of it), and of them at most `scan`: sorting all 180, or a partial sort's heap, was most of
  // a roll search's time.
  // (A lag whose value is NaN, which a spectrum holding NaN at 0 or 89 gives, is never a peak.)
  const int scan = std::clamp(static_cast<int>(options.quantile * static_cast<float>(kLags)), 0, kLags);
  float best = -std::numeric_limits<float>::infinity();
  for (const double v : re) {
    if (!std::isnan(v)) best = std::max(best, static_cast<float>(v));
  }
  const float bar = best * options.accept_threshold;
  std::array<std::pair<float, int>, kLags> scored;
  std::size_t kept = 0;
  for (int n = 0; n < kLags; ++n) {
    const auto value = static_cast<float>(re[static_cast<std::size_t>(n)]);
    if (!std::isnan(value) && !(value < bar)) scored[kept++] = {value, n};
  }
  const auto better = [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); };
  const std::size_t ordered = std::min(kept, static_cast<std::size_t>(scan));
  if (ordered > 0 && ordered < kept) std::nth_element(scored.begin(), scored.begin() + static_cast<std::ptrdiff_t>(ordered) - 1, scored.begin() + static_cast<std::ptrdiff_t>(kept), better);
  std::sort(scored.begin(), scored.begin() + static_cast<std::ptrdiff_t>(ordered), better);
  constexpr int kPeakDistance = 5;
  std::vector<int> peaks;
  std::vector<float> angles;
  for (std::size_t i = 0; i < ordered && static_cast<int>(peaks.size()) < options.max_peaks; ++i) {
    const int lag = scored[i].second;
    // PCL's neighbourhood test, one-sided wrap included.
    const bool near = std::any_of(peaks.begin(), peaks.end(), [lag](int p) {
      return std::abs(p - lag) <= kPeakDistance || std::abs(p - (lag - kLags)) <= kPeakDistance;
    });
    if (near) continue;
    peaks.push_back(lag);
    angles.push_back(static_cast<float>(lag) * (360.0f / static_cast<float>(kLags)));
  }
  return angles;
}

Transform crh_alignment(const Eigen::Vector3d& view_centroid, const Eigen::Vector3d& scene_centroid, double roll_deg) {
  const Eigen::Matrix3d roll = Eigen::AngleAxisd(-roll_deg * kPi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d M = ray_to_z(view_centroid).transpose() * roll * ray_to_z(scene_centroid);
  // H carries scene coordinates into the view's; its inverse carries the view into the scene.
  const Transform H = make_transform(M, view_centroid - M * scene_centroid);
  return H.inverse();
}

}  // namespace viewpose
