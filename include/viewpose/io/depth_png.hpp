#pragma once
// Depth images stored as 16-bit single-channel PNG, the format of Kinect/Xtion tools and of BOP.
// A stored value v means v * metres_per_unit metres; 0 means no measurement. BOP's depth_scale is in
// millimetres per unit, so metres_per_unit = depth_scale / 1000 (1 mm per unit by default).
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "viewpose/core/depth_image.hpp"

namespace viewpose {

inline constexpr int kMaxDepthImageSide = 16384;

DepthImage read_depth_png(const std::filesystem::path& path, double metres_per_unit);
/// Decodes PNG bytes; refuses anything but 16-bit greyscale, naming what it found instead.
DepthImage decode_depth_png(std::span<const std::uint8_t> bytes, std::string_view name, double metres_per_unit);

/// Writes `depth` rounded to the nearest unit; NaN becomes 0. Throws viewpose::Error when a depth
/// does not fit in 16 bits at this scale. Atomic.
void write_depth_png(const std::filesystem::path& path, const DepthImage& depth, double metres_per_unit);
std::vector<std::uint8_t> encode_depth_png(const DepthImage& depth, double metres_per_unit);

}  // namespace viewpose
