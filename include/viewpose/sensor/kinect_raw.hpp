#pragma once
// Kinect v1 raw depth: 11-bit disparity values, as the sensor sends them (libfreenect's
// FREENECT_DEPTH_11BIT mode and fakenect recordings), 2047 meaning no measurement. Depth follows
// from disparity by the widely used fit z = 1 / (a + b d) (N. Burrus' calibration of the Kinect,
// a = 3.3309495161 1/m, b = -0.0030711016 1/m), which gives the sensor's quantization: about
// 3 mm per step at 1 m and 7 mm at 1.5 m. A device's own calibration differs by a few per cent;
// pass a camera file for exact intrinsics, the depth scale is this fit's.
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "viewpose/core/depth_image.hpp"

namespace viewpose {

inline constexpr std::uint16_t kKinectNoDisparity = 2047;

/// Depth in metres of a raw disparity; NaN for 2047, and for values that fall outside 0.3-10 m.
float kinect_disparity_to_depth_m(std::uint16_t raw);
/// The raw disparity nearest a depth; 2047 for NaN and depths outside 0.3-10 m.
std::uint16_t kinect_depth_to_disparity(float z_m);
/// A depth image from a raw disparity buffer of width x height values (row-major).
DepthImage depth_from_kinect_disparity(std::span<const std::uint16_t> raw, int width, int height);

/// Writes `frames` (640 x 480, the only size fakenect plays) as a fakenect recording, libfreenect's
/// replay format: DIR/INDEX.txt names one file per frame, d-TIME-TIMESTAMP.pgm, each a one-line PGM
/// header followed by the raw disparities as little-endian 16-bit values (the buffer the Kinect
/// delivers, as fakenect-record stores it), `fps` frames a second. Replay it with libfreenect's
/// fakenect library (FAKENECT_PATH=DIR, LD_LIBRARY_PATH=/usr/lib/<arch>/fakenect). Each file is
/// written atomically, INDEX.txt last.
void write_fakenect_recording(const std::filesystem::path& dir, std::span<const DepthImage> frames, double fps = 30.0);

}  // namespace viewpose
