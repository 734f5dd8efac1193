#pragma once
// How well a guessed pose lays a database view over a scene region, before any refinement: the
// cheap test that orders a region's hypotheses, so that ICP and verification spend their time on
// the likeliest first and a search with a budget stops early without losing the object.
//
// Both ways round, because each alone is fooled: the region's points must lie near the model's
// surface (a small object laid inside a large region fails), and the view's points must lie near the
// region's (a large object's surface also passes near every point of a small region, but most of
// its view then lies where the scene has nothing). Nearness is counted in cells of an occupancy grid
// (core/occupancy_grid): a point in an occupied cell counts 1, next to one 1/2.
#include <cstddef>
#include <span>

#include <Eigen/Core>

#include "viewpose/core/occupancy_grid.hpp"
#include "viewpose/core/transform.hpp"

namespace viewpose {

/// The share of `points`, moved by T_grid_points, that lie near the grid's points (1 in an
/// occupied cell, 1/2 in a cell touching one), from at most `max_points` of them evenly spread.
double overlap(std::span<const Eigen::Vector3f> points, const Transform& T_grid_points, const OccupancyGrid& grid,
               std::size_t max_points = 64);

struct CoarseFitInputs {
  std::span<const Eigen::Vector3f> region_points;  ///< camera frame
  const OccupancyGrid* region_grid = nullptr;      ///< of region_points
  std::span<const Eigen::Vector3f> view_points;    ///< the database view's, its camera frame
  const OccupancyGrid* model_grid = nullptr;       ///< of the object's model points, object frame
};

/// The lesser of the two overlaps (region on the model, view on the region) at the pose that
/// carries the view's camera frame into the scene's (T_camera_view) and the object into the
/// camera (T_camera_object = T_camera_view * T_view_object). In [0, 1].
double coarse_fit(const CoarseFitInputs& in, const Transform& T_camera_view, const Transform& T_camera_object,
                  std::size_t max_points = 64);

/// The same for a pose no view gave (point pair votes): the model's points whose normals face the
/// camera (the origin) at T_camera_object stand in for the view's. `model_points` and
/// `model_normals` (outward) are in the object frame. In [0, 1]; 0 when none faces the camera.
double coarse_fit_facing(std::span<const Eigen::Vector3f> region_points, const OccupancyGrid& region_grid,
                         std::span<const Eigen::Vector3f> model_points, std::span<const Eigen::Vector3f> model_normals,
                         const OccupancyGrid& model_grid, const Transform& T_camera_object, std::size_t max_points = 64);

}  // namespace viewpose
