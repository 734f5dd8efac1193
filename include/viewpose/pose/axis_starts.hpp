#pragma once
// Starting poses for a thin object seen edge-on, from the shapes of the region and the object.
//
// A book or a board seen along its edge shows a strip as wide as it is thick: its side and, seen
// from above, its top, foreshortened. No rendered view stands exactly at that angle, and a view a
// few degrees off shows a face the strip does not, so the views' poses miss it (the thesis's
// failure case, its Figure 16). The strip itself gives most of the pose: its narrow direction in
// the image is the object's thin axis, and its near side where the object's near side is. What it
// does not give, the turn of the object's plane about that axis, is sampled; ICP and verification
// finish and judge these starts as any other.
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/point_cloud.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

/// The region's shape as the camera sees it: the points projected onto the plane square to the
/// ray through their mean, `width_m` the extent of the middle `share` of them (from the quantile
/// (1 - share) / 2 to its mirror: stray points do not widen it) along the narrower of that
/// plane's two principal axes (`across`, unit, square to the ray), `length_m` the same along the
/// wider. A thin object seen edge-on gives a strip whose width is its thickness and
/// whose `across` is its thin axis, whether its top shows too or not. Zeros for fewer than two
/// finite points.
struct StripSize {
  double width_m = 0;
  double length_m = 0;
  Eigen::Vector3d across = Eigen::Vector3d::Zero();
};
StripSize strip_size(std::span<const Eigen::Vector3f> points, double share);

/// Poses T_camera_object of a thin object seen edge-on: its thinnest principal axis (`object`'s
/// third, of `model_points` in the object frame) along `across` either way, and its plane turned
/// about it in `turns` even steps (so the nearest is within half a step of any turn: the region's
/// own axes in that plane are no guide, a spine and a foreshortened top tilt them). Each is placed
/// as the strip shows it (seen from the ray through the region's mean, with the directions square
/// to it taken as parallel): the middle of the object's outline across the image at the middle of
/// the region's, its nearest point along the ray as near as the region's (the region's extremes,
/// untrimmed: a segmented cloud's stray pixels lie behind its surface, not before it, and ICP
/// takes up a few millimetres). 2 x `turns` poses; none when the region or the model has no
/// finite point, `turns` is below 1, or `across` is no direction or lies along the ray.
std::vector<Transform> edge_on_poses(const PrincipalAxes& object, std::span<const Eigen::Vector3f> model_points,
                                     std::span<const Eigen::Vector3f> region_points, const Eigen::Vector3d& across, int turns);

}  // namespace viewpose
