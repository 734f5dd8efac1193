#pragma once
// An object's symmetries: the motions of its own frame that leave its surface where it was, so that
// poses differing by one of them look the same to any sensor. As BOP's models_info.json: discrete
// ones (a box's half turns) as transforms, continuous ones (a can's axis) as an axis and a point on
// it. Found from the mesh (find_symmetries), or read from BOP, and used to report one canonical pose
// among the equivalent ones (canonical_pose), so that poses do not flip from frame to frame.
#include <cstdint>
#include <vector>

#include "viewpose/core/mesh.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

struct ContinuousSymmetry {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();  ///< a point on the axis, object frame
};

struct Symmetries {
  std::vector<Transform> discrete;  ///< object-frame transforms, the identity not included
  std::vector<ContinuousSymmetry> continuous;
  bool empty() const { return discrete.empty() && continuous.empty(); }
};

struct SymmetryOptions {
  /// A motion is a symmetry when 99 % of the surface samples land within this share of the diameter
  /// of the surface. Measured on YCB-Video's scanned meshes: at 1 % the foam brick's half turn that
  /// BOP lists is missed (its scan is not exact); 2 % finds it and still no symmetry in the jug or
  /// the mug (their handles are a few % of the surface).
  double tolerance_fraction = 0.02;
  std::size_t samples = 1500;         ///< surface points tested per candidate motion
  std::size_t dense_samples = 30000;  ///< surface points that index the surface for the distance look-up
  std::uint64_t seed = 1;
};

/// Symmetries of a closed or open mesh: rotations about its principal axes through its surface
/// centroid, continuous (every angle) or n-fold (n = 2, 3, 4, 6), combined into the group they make.
/// An empty result for an object with a distinguishing part (a jug's handle).
Symmetries find_symmetries(const TriangleMesh& mesh, const SymmetryOptions& options = {});

/// Every transform the symmetries make, the identity first; each continuous one as
/// `continuous_steps` equal turns, each combined with every discrete one.
std::vector<Transform> symmetry_transforms(const Symmetries& symmetries, int continuous_steps = 360);

/// Among the poses T_camera_object * S that the symmetries make equivalent, the one whose rotation is
/// nearest a fixed reference: the same answer for every equivalent input. The reference stands the
/// object as it was modelled, its z up, for a camera looking anywhere from level to straight down
/// without roll (a box's z within 70 degrees of the reference's, a can's within 90, come back up):
/// object z toward (0, -1, -1) / sqrt 2 in the camera frame (up in the image and toward the
/// camera), object x along the camera's x. CAD models are mostly drawn standing on their base with
/// z up (YCB-Video's, LineMOD's, T-LESS's), and objects stand so on a table: a can whose ends look
/// alike is then reported upright, as it stands, not upside down. (The camera's own axes, the
/// reference before, put the object's z along the viewing direction, pointing down into a table
/// seen from above: real YCB-Video frames, AR 0.495 -> 0.511; the can upright, 180 -> 20 degrees
/// off the truth about its axis.) What depth cannot see (a printed front) stays a coin flip. The
/// recognizer then takes the up from the plane the object rests on where there is one (below).
Transform canonical_pose(const Transform& T_camera_object, const Symmetries& symmetries);

/// The same with the scene's own up, a vector in the camera frame (the normal of the plane the
/// object stands on, resting_plane_up): the reference is object z along `up_camera` and object x
/// along the heading of the camera's view (its viewing direction made square to up, turned a
/// quarter turn about up; for a camera looking nearly along up, its x made square to up). No roll
/// of the camera changes that heading, so the pose reported stays put in the world while the
/// camera rolls; for a camera not rolled it is the fixed reference above. A zero or non-finite
/// up gives the fixed reference.
Transform canonical_pose(const Transform& T_camera_object, const Symmetries& symmetries, const Eigen::Vector3d& up_camera);

}  // namespace viewpose
