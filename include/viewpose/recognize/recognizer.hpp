#pragma once
// The whole pipeline on one frame: segment, describe each cluster, match it against the view
// database, and for each match in order turn the CRH roll peaks into poses, refine each with ICP
// and verify it; the first pose that passes is the detection (or, with keep_best, the best of all).
#include <memory>
#include <string>
#include <vector>

#include "viewpose/database/view_database.hpp"
#include "viewpose/describe/crh.hpp"
#include "viewpose/pose/icp.hpp"
#include "viewpose/pose/verify.hpp"
#include "viewpose/recognize/frame.hpp"
#include "viewpose/segment/segmentation.hpp"

namespace viewpose {

struct RecognizerOptions {
  SegmentOptions segment;
  std::size_t matches = 20;      ///< nearest views tried per cluster and object (thesis: 20, one object)
  /// CRH peaks: up to 10 rolls per view, down to half the best peak. PCL's 5 and 0.8 missed 1 of 100
  /// frames of the simulated seed experiment (a narrow side view); these found all 100, still
  /// without a false positive (docs/RESULTS.md).
  RollOptions roll = {10, 0.2f, 0.5f};
  float icp_voxel_m = 0.005f;    ///< the cluster is thinned to this for ICP (thesis: 5 mm)
  IcpOptions icp;
  VerifyOptions verify;
  bool keep_best = false;        ///< try every hypothesis, keep the best accepted (slower)
  /// Once a pose passes, also try it turned half a turn about each of the object's axes (refined and
  /// verified in turn) and keep the best: objects that are nearly symmetric (a jug whose handle is a
  /// small share of its surface) otherwise come out the wrong way round about as often as not.
  bool try_half_turns = true;
  double max_cluster_size_factor = 1.5;  ///< clusters wider than this x the largest object are skipped
};

struct Detection {
  int object_id = 0;
  std::string object_name;
  Transform T_camera_object = Transform::Identity();  ///< metres
  double score = 0;          ///< verification score in [0, 1]: share of the model and cluster explained
  double icp_fitness = 0;    ///< share of cluster points with a model correspondence
  double icp_rmse_m = 0;     ///< RMS point-to-plane residual
  int match_rank = 0;        ///< 0 = the nearest view
  float roll_deg = 0;        ///< the CRH roll that led to it
  double runner_up_score = 0;  ///< best score of the half-turned alternatives (0 if none passed): a margin
  std::size_t cluster_points = 0;
  Verification verification;
};

struct StageTimes {
  double downsample_ms = 0, segment_ms = 0, normals_ms = 0, vfh_ms = 0, match_ms = 0, crh_ms = 0, icp_ms = 0,
         verify_ms = 0, total_ms = 0;
};

struct Recognition {
  std::vector<Detection> detections;
  StageTimes times;
  std::size_t clusters = 0;
  std::size_t hypotheses = 0;  ///< poses refined and verified
};

class Recognizer {
 public:
  explicit Recognizer(const ViewDatabase& db, RecognizerOptions options = {});
  ~Recognizer();
  Recognition recognize(const Frame& frame) const;
  const RecognizerOptions& options() const { return options_; }

 private:
  const ViewDatabase& db_;
  RecognizerOptions options_;
  std::vector<std::unique_ptr<IcpTarget>> targets_;  // one per object
  double largest_diameter_m_ = 0;
};

}  // namespace viewpose
