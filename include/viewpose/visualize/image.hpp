#pragma once
// Pictures for people: depth shown in colour, and several images tiled into one sheet.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "viewpose/core/depth_image.hpp"

namespace viewpose {

struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< 3 bytes per pixel, row-major

  RgbImage() = default;
  RgbImage(int w, int h, std::uint8_t grey = 0);
  void set(int u, int v, std::uint8_t r, std::uint8_t g, std::uint8_t b);
};

/// Depth in colour: near is warm (red, yellow), far is cool (blue), no measurement is black.
RgbImage colourize_depth(const DepthImage& depth, float near_m, float far_m);

/// A straight line, clipped to the image.
void draw_line(RgbImage& image, Eigen::Vector2d a, Eigen::Vector2d b, const std::array<std::uint8_t, 3>& colour);

/// One colour per detection index, distinct for the first eight.
std::array<std::uint8_t, 3> palette(std::size_t i);

/// Images side by side, `columns` to a row, on a grey background with `gap` pixels between.
RgbImage tile_images(std::span<const RgbImage> images, int columns, int gap = 4);

}  // namespace viewpose
