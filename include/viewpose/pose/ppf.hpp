#pragma once
// Pose hypotheses from point pair features, a second source beside the VFH match that needs no
// clean cluster: an object touching another, or half hidden, still shows pairs of its own surface
// points. Written from Drost et al., "Model globally, match locally: efficient and robust 3D object
// recognition" (CVPR 2010), with refinements of Vidal, Lin and Martí, "6D pose estimation using
// an improved method based on point pair features" (ICCAR 2018): sampling that keeps points whose
// normals differ, look-ups that also take the neighbouring bin of a feature near a bin's edge, and
// votes clustered into poses.
//
// A pair of oriented points (m1, n1), (m2, n2) has the feature
//   F = (|d|, angle(n1, d), angle(n2, d), angle(n1, n2)),  d = m2 - m1,
// which no rigid motion changes. The model's pairs are stored by their quantized F. A scene point
// s1, taken as lying on the model at m1, aligns with it up to a rotation alpha about the normal;
// each scene pair (s1, s2) whose F matches a model pair (m1, m2) votes for (m1, alpha). The peak
// of a reference point's votes is a pose; poses from all reference points are clustered, and the
// clusters with the most votes are the hypotheses.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "viewpose/core/transform.hpp"

namespace viewpose {

struct PpfOptions {
  /// Points are sampled, and pair distances quantized, at this fraction of the object's diameter
  /// (Drost: 0.05; finer sampling costs pairs quadratically).
  double sample_fraction = 0.05;
  int angle_bins = 30;  ///< 2 pi / this is the angle step (12 degrees), for the features and alpha; divides 13440
  /// Two sampled points are kept in one cell where their normals differ by more than this (Vidal):
  /// the edges of a box keep both faces.
  double normal_split_deg = 30;
  int reference_stride = 5;  ///< every k-th sampled scene point is a reference point (Drost: 1 in 5)
  /// At most this many reference points per scene (a larger stride where 1 in reference_stride
  /// would give more; 0: no bound), so that a region's votes take a bounded time: on the real
  /// YCB-V frames 40 cast the votes in 0.73 of the time of 1 in 5 and found the same poses (20 too,
  /// in half the time; docs/BENCHMARK.md, "Point pair votes").
  std::size_t max_reference_points = 40;
  /// A feature within this share of a bin's width from its edge also looks up the neighbouring bin
  /// (Vidal's answer to noise moving features across bin edges). 0: the own bin only. Measured on
  /// the jug's cluster (BM_PpfHypothesesJugCluster): 0.25 casts 4.7 times the votes of 0, and the
  /// analytic tests pass with either; to be chosen on real clutter.
  double spread_fraction = 0;
  /// A feature that more model pairs share than the model has points is found, on average, at
  /// every point of the model: it says nothing about where on the model a scene pair lies (two
  /// points of one flat face match every pair of every face). Its look-ups cast no votes. Such
  /// features cast most of the votes on the jug, and took most of the time.
  double max_bucket_per_point = 1.0;
  /// Poses closer than these (translation as a fraction of the diameter, rotation) are one pose.
  double cluster_distance_fraction = 0.1;
  double cluster_angle_deg = 24;
  std::size_t max_hypotheses = 10;  ///< the clusters with the most votes, most first
};

/// Throws Error (one line) unless sample_fraction is in (0, 1), angle_bins >= 4 divides 13440 and
/// reference_stride >= 1: what PpfModel checks first, for callers that make their tables later.
void check_ppf_options(const PpfOptions& options);

/// Oriented points: positions and unit normals, one each.
struct OrientedPoints {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
  std::size_t size() const { return points.size(); }
};

/// Sampling on a grid of `step_m` cubes: in each cube the mean of its points, one per group of
/// normals that differ by more than `normal_split_deg`. Points with a non-finite normal are left out.
/// The same code samples the model and the scene, so that their pairs are alike.
OrientedPoints ppf_sample(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, float step_m,
                          double normal_split_deg);

struct PpfHypothesis {
  Transform T_camera_object = Transform::Identity();
  double votes = 0;          ///< summed over the poses clustered into it
  std::size_t poses = 0;     ///< reference points whose peak fell into this cluster
};

/// One object's pair table, as plain data that the view database stores (made once, with the
/// database, rather than in the first frame that asks for votes: about 0.1 s an object). Every
/// ordered pair of the object's sampled points no farther apart than its diameter, by quantized
/// feature, with the pair's first point and its angle about that point's normal.
struct PpfTable {
  // What shaped the table (PpfOptions' sample_fraction, angle_bins and normal_split_deg); the
  // other options act when votes are cast, and may differ from one recognizer to another.
  double diameter_m = 0;
  double sample_fraction = 0;
  int angle_bins = 0;
  double normal_split_deg = 0;
  OrientedPoints sampled;  ///< object frame
  std::vector<std::uint32_t> key_start;  ///< entries of key k: [key_start[k], key_start[k + 1])
  /// A pair: its first point's index into `sampled` shifted left by kAlphaBits, or'd with its
  /// angle in units of 2 pi / kAlphaUnits. One word a pair: the tables are most of the votes'
  /// memory traffic and of a database's bytes.
  std::vector<std::uint32_t> entries;

  static constexpr std::uint32_t kAlphaUnits = 30 * 64 * 7;  ///< 13440: divisible by 30, 40, 45, 60, 64, ...
  static constexpr int kAlphaBits = 14;  ///< 2^14 > kAlphaUnits
  static constexpr std::uint32_t kMaxPoints = std::uint32_t{1} << (32 - kAlphaBits);  ///< 262144 sampled points at most
  static constexpr std::uint32_t entry(std::uint32_t point, std::uint32_t alpha) { return point << kAlphaBits | alpha; }
  bool empty() const { return entries.empty(); }
  std::size_t bytes() const;  ///< what it holds, about what it takes in a file
  /// Whether it was made with these shaping options (and so serves a recognizer that has them).
  bool made_with(const PpfOptions& options) const;
};

/// Makes the pair table of an object from `points` and outward unit `normals` of its surface
/// (object frame, metres). Throws Error (one line) on bad options or a model of fewer than two
/// oriented points.
PpfTable make_ppf_table(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, double diameter_m,
                        const PpfOptions& options = {});

/// Throws Error (one line, naming what is wrong) unless `table` is one make_ppf_table could have
/// made: sizes that agree, keys in order, every pair naming a sampled point. What a database read
/// from a damaged file is checked with, so that voting never reads out of bounds.
void check_ppf_table(const PpfTable& table);

/// Votes for an object's poses from its pair table.
class PpfModel {
 public:
  /// Makes the table (make_ppf_table).
  PpfModel(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, double diameter_m,
           const PpfOptions& options = {});
  /// Votes with a table made earlier (a database's), checked with check_ppf_table; the table's own
  /// shaping options hold, `options` gives the rest.
  PpfModel(std::shared_ptr<const PpfTable> table, const PpfOptions& options = {});

  const PpfTable& table() const { return *table_; }
  const OrientedPoints& sampled() const { return table_->sampled; }
  std::size_t pairs() const { return table_->entries.size(); }
  double diameter_m() const { return table_->diameter_m; }
  float sample_step_m() const { return step_m_; }
  double normal_split_deg() const { return table_->normal_split_deg; }
  const PpfOptions& options() const { return options_; }

  /// Hypotheses for this object in `scene` (sampled with ppf_sample at sample_step_m() and
  /// normal_split_deg(), normals towards the camera, camera frame), most votes first.
  std::vector<PpfHypothesis> hypotheses(const OrientedPoints& scene) const;

 private:
  void prepare();
  std::size_t key(int d, int a1, int a2, int a3) const;

  std::shared_ptr<const PpfTable> table_;
  PpfOptions options_;
  float step_m_ = 0;
  int distance_bins_ = 0, feature_angle_bins_ = 0;
  std::vector<Transform> T_local_model_;     ///< per sampled point: it at the origin, its normal along +x
  /// phi's alpha bin for each alpha_scene - alpha_model + kAlphaUnits (in [1, 2 kAlphaUnits)): one
  /// table read per vote in place of a modulo and a division by a run-time divisor.
  std::vector<std::uint16_t> phi_bin_;
};

}  // namespace viewpose
