#pragma once
// 8-bit RGB PNG output, for pictures made for people (contact sheets, pose overlays).
#include <cstdint>
#include <filesystem>
#include <vector>

#include "viewpose/visualize/image.hpp"

namespace viewpose {

std::vector<std::uint8_t> encode_rgb_png(const RgbImage& image);
void write_rgb_png(const std::filesystem::path& path, const RgbImage& image);  // atomic

}  // namespace viewpose
