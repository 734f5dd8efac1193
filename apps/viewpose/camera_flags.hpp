#pragma once
// The camera options every command that reads depth images shares: intrinsics from a BOP
// camera.json (--camera) or from the command line (--intrinsics FX FY CX CY), and the depth scale.
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "viewpose/io/bop.hpp"

namespace viewpose::cli {

struct CameraFlags {
  std::string camera_file;
  std::vector<double> intrinsics;
  std::optional<double> depth_scale_mm;

  void add_to(CLI::App& cmd);
  /// The camera the flags describe, if any (image size 0 when only --intrinsics was given).
  std::optional<BopCamera> camera() const;
  /// Millimetres per depth unit: --depth-scale, else the camera file's, else 1.
  double depth_scale() const;
};

}  // namespace viewpose::cli
