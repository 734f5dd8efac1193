#pragma once
// What a file holds, for `viewpose info` and for people checking their data: the kind of file, its
// size in points or vertices and faces, its layout, its fields, and where its coordinates lie.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/point_cloud.hpp"
#include "viewpose/core/units.hpp"

namespace viewpose {

struct FileInfo {
  std::string kind;  ///< e.g. "PCD point cloud (binary_compressed, v0.7)", "16-bit depth PNG"
  std::size_t points = 0;      ///< points, vertices or pixels
  std::size_t valid_points = 0;  ///< finite points, or pixels with a depth
  std::size_t faces = 0;
  int width = 0, height = 0;  ///< organized grid or image size; height 1 = unorganized
  std::vector<std::string> fields;
  BoundingBox bbox;                       ///< in the unit named by bbox_unit
  std::optional<LengthUnit> bbox_unit;    ///< known unit of the coordinates, if the format fixes it
  std::optional<UnitGuess> unit_guess;    ///< for formats that carry no unit
  std::vector<std::string> notes;         ///< further facts (camera, images, objects, ...)
  std::vector<std::string> problems;      ///< readable, but not usable as is (e.g. no valid point)
};

struct InspectOptions {
  double depth_png_metres_per_unit = 0.001;  ///< scale for bare depth PNGs
  /// Intrinsics for depth PNGs: when set, the points they make are measured too. An image size
  /// of 0 takes the image's own; another size must match it.
  std::optional<CameraIntrinsics> camera;
};

/// Reads `path` (PCD, PLY, a mesh assimp knows, a 16-bit depth PNG, BOP json or results CSV, or a
/// BOP dataset folder). Throws viewpose::Error when the file cannot be read.
FileInfo inspect_file(const std::filesystem::path& path, const InspectOptions& options = {});

}  // namespace viewpose
