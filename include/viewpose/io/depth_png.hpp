#pragma once
// Depth images stored as 16-bit single-channel PNG, the format of Kinect/Xtion tools and of BOP.
// A stored value v means v * metres_per_unit metres; 0 means no measurement. BOP's depth_scale is in
// millimetres per unit, so metres_per_unit = depth_scale / 1000 (1 mm per unit by default).
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "viewpose/core/depth_image.hpp"

namespace viewpose {

inline constexpr int kMaxDepthImageSide = 16384;

DepthImage read_depth_png(const std::filesystem::path& path, double metres_per_unit);

/// The stored values as they are, in the file's units (0 = no measurement): depth_from_units()
/// (core/depth_image.hpp) turns them into metres exactly as read_depth_png does.
struct DepthPngUnits {
  int width = 0;
  int height = 0;
  std::vector<std::uint16_t> units;  ///< row-major
};
DepthPngUnits read_depth_png_units(const std::filesystem::path& path);
DepthPngUnits decode_depth_png_units(std::span<const std::uint8_t> bytes, std::string_view name);
/// Decodes PNG bytes; refuses anything but 16-bit greyscale, naming what it found instead.
DepthImage decode_depth_png(std::span<const std::uint8_t> bytes, std::string_view name, double metres_per_unit);

/// A structured-light or time-of-flight camera measures about 0.3 to 5 m. When the median valid
/// depth of an image read at `mm_per_unit` lies outside that, a one-line warning naming the depth
/// scale (a power of ten times this one) that brings the median nearest 1 m, and what it gives;
/// empty when the depth is plausible or there is none. A YCB-Video PNG (0.1 mm per unit) read at
/// 1 mm per unit has its median near 8 m.
std::string depth_scale_warning(const DepthImage& depth, double mm_per_unit);

/// Writes `depth` rounded to the nearest unit; NaN becomes 0. Throws viewpose::Error when a depth
/// does not fit in 16 bits at this scale. Atomic.
void write_depth_png(const std::filesystem::path& path, const DepthImage& depth, double metres_per_unit);
std::vector<std::uint8_t> encode_depth_png(const DepthImage& depth, double metres_per_unit);

}  // namespace viewpose
