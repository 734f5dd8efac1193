#pragma once
// The frame as a whole: each pixel's measured surface is explained by at most one detection.
// verify_pose judges one hypothesis at a time, so two poses of one object (found in two pieces of
// its cluster), or a wrong pose laid over a right one, can each pass alone. Here every accepted
// pose claims the pixels where its drawn surface meets the measured one; taken most confident
// first, a pose is kept only if most of what it explains is not explained already by one kept
// before it. This is the part of PCL's global hypothesis verification that one-at-a-time
// verification cannot do (a pixel is explained once), without its optimisation over subsets: the
// hypotheses reaching it are few and already verified, and the most confident first is the order
// a robot would trust.
#include <cstdint>
#include <span>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/pose/verify.hpp"

namespace viewpose {

struct SceneClaimOptions {
  /// A pose is dropped when more than this share of its claimed pixels is claimed by a pose kept
  /// before it. Distinct objects share only the pixels along where they touch (a few percent);
  /// two poses of one object share nearly all.
  double max_shared_fraction = 0.5;
  /// ... or when fewer than this many of its claimed pixels are its own (camera pixels): the
  /// evidence it alone explains must be as much as verification asks of any pose.
  std::size_t min_own_pixels = 150;
};

/// The pixels (v * width + u, ascending) where the model drawn at T_camera_object is the measured
/// surface: both present, and within verification's depth tolerance of each other.
std::vector<std::uint32_t> claimed_pixels(const VerifyModel& model, const Transform& T_camera_object,
                                          const DepthImage& observed, const CameraIntrinsics& K,
                                          const VerifyOptions& verify = {});

struct ClaimVerdict {
  bool kept = false;
  std::size_t claimed = 0;  ///< pixels the pose explains
  std::size_t shared = 0;   ///< of those, explained by a pose kept before it
};

/// Claims (each ascending, as claimed_pixels gives them) in order of priority, first the most
/// trusted: which are kept. Plain sets in, so the rule can be checked without any rendering.
std::vector<ClaimVerdict> resolve_claims(std::span<const std::vector<std::uint32_t>> claims_in_priority_order,
                                         const SceneClaimOptions& options = {});

}  // namespace viewpose
