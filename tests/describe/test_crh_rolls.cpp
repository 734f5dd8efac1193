// The roll search (crh_roll_angles) against the textbook computation it stands for: the phase
// correlation of the two spectra, its inverse transform at every lag one complex product at a time,
// and a full stable sort of the lags. The fast code (a table of roots read row by row, the even and
// odd harmonics summed apart over half the lags, compiled for AVX2 too, the magnitude without a
// call, only the lags at or above the peak bar ordered, and at most quantile x 180 of them) must
// find the same angles, bit for bit, on thousands of seeded random histograms: the CRHs of random
// normals, and raw random spectra.
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "viewpose/describe/crh.hpp"

namespace viewpose {
namespace {

std::vector<float> reference_roll_angles(const Crh& view, const Crh& scene, const RollOptions& options) {
  constexpr int kBins = 90, kLags = 180;
  std::vector<std::complex<double>> product(kLags, 0.0);
  product[0] = static_cast<double>(view[0]) * scene[0];
  for (int k = 1; k < kBins / 2; ++k) {
    const std::complex<float> a(view[static_cast<std::size_t>(2 * k - 1)], -view[static_cast<std::size_t>(2 * k)]);
    const std::complex<float> b(scene[static_cast<std::size_t>(2 * k - 1)], scene[static_cast<std::size_t>(2 * k)]);
    const std::complex<float> ab = a * b;
    const float magnitude = std::abs(ab);
    product[static_cast<std::size_t>(k)] = magnitude > 0 ? std::complex<double>(ab / magnitude) : 0.0;
  }
  product[kBins - 1] = static_cast<double>(view[kBins - 1]) * scene[kBins - 1];
  std::vector<std::pair<float, int>> scored;
  for (int n = 0; n < kLags; ++n) {
    double re = 0;
    for (int k = 0; k < kLags; ++k) {
      if (product[static_cast<std::size_t>(k)] == 0.0) continue;
      const std::complex<double> root = std::polar(1.0, 2 * std::numbers::pi * ((k * n) % kLags) / kLags);
      re += (product[static_cast<std::size_t>(k)] * root).real();
    }
    scored.emplace_back(static_cast<float>(re), n);
  }
  std::stable_sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<int> peaks;
  std::vector<float> angles;
  const int scan = static_cast<int>(options.quantile * static_cast<float>(kLags));
  for (int i = 0; i < scan && static_cast<int>(peaks.size()) < options.max_peaks; ++i) {
    const auto [value, lag] = scored[static_cast<std::size_t>(i)];
    if (value < scored[0].first * options.accept_threshold) continue;
    if (std::any_of(peaks.begin(), peaks.end(), [lag = lag](int p) { return std::abs(p - lag) <= 5 || std::abs(p - (lag - kLags)) <= 5; })) continue;
    peaks.push_back(lag);
    angles.push_back(static_cast<float>(lag) * 2.0f);
  }
  return angles;
}

Crh crh_of_random_normals(std::mt19937& rng) {
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::uniform_int_distribution<int> count(3, 400);
  std::vector<Eigen::Vector3f> normals(static_cast<std::size_t>(count(rng)));
  // Some of each: normals spread all round, and bunched about one direction (a box face).
  const Eigen::Vector3f bunch = Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized();
  for (auto& n : normals) n = (bunch * 2.0f * std::abs(g(rng)) + Eigen::Vector3f(g(rng), g(rng), g(rng))).normalized();
  return compute_crh(normals, Eigen::Vector3f(0.1f * g(rng), 0.1f * g(rng), 1.0f));
}

Crh random_spectrum(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Crh c;
  for (float& x : c) x = u(rng);
  c[0] = 1.0f;
  for (std::size_t i = 1; i < c.size(); i += 7) c[i] = 0.0f;  // some harmonics absent
  return c;
}

TEST(CrhRollAngles, EqualTheTextbookPhaseCorrelationBitForBit) {
  std::mt19937 rng(20261203);
  // The defaults, the recognizer's, every lag, few lags; then bars that let more lags pass than
  // are ordered (the selection), none ordered, and (with a positive best) a bar below every lag
  // and one above them all.
  const RollOptions options[] = {{},           {10, 0.2f, 0.5f},  {3, 1.0f, 0.0f},   {5, 0.05f, 0.9f},
                                 {5, 0.05f, 0.0f}, {5, 0.0f, 0.8f}, {5, 0.2f, -1.0f}, {5, 0.2f, 1.5f}};
  int compared = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const bool raw = trial % 3 == 2;
    const Crh view = raw ? random_spectrum(rng) : crh_of_random_normals(rng);
    const Crh scene = raw ? random_spectrum(rng) : crh_of_random_normals(rng);
    for (const RollOptions& o : options) {
      ASSERT_EQ(crh_roll_angles(view, scene, o), reference_roll_angles(view, scene, o)) << "trial " << trial;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 12000);
}

TEST(CrhRollAngles, ARolledHistogramIsFoundAtItsRoll) {
  // The CRH of normals turned by 30 degrees about the viewing ray (z, the centroid on it) is the
  // same histogram shifted by 30 / 4 bins... found at 30 degrees, best first.
  std::mt19937 rng(7);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> normals(300), turned;
  for (auto& n : normals) n = Eigen::Vector3f(3.0f * g(rng), g(rng), -0.5f + 0.2f * g(rng)).normalized();
  const Eigen::Matrix3f R = Eigen::AngleAxisf(static_cast<float>(std::numbers::pi / 6), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  for (const auto& n : normals) turned.push_back(R * n);
  const Eigen::Vector3f centroid(0, 0, 1);
  const std::vector<float> rolls = crh_roll_angles(compute_crh(normals, centroid), compute_crh(turned, centroid));
  ASSERT_FALSE(rolls.empty());
  EXPECT_NEAR(rolls[0], 30.0f, 4.0f);
}

}  // namespace
}  // namespace viewpose
