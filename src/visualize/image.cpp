#include "viewpose/visualize/image.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace viewpose {

RgbImage::RgbImage(int w, int h, std::uint8_t grey)
    : width(w), height(h), rgb(3 * static_cast<std::size_t>(w) * static_cast<std::size_t>(h), grey) {}

void RgbImage::set(int u, int v, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  if (u < 0 || v < 0 || u >= width || v >= height) return;
  std::uint8_t* p = rgb.data() + 3 * (static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u));
  p[0] = r;
  p[1] = g;
  p[2] = b;
}

RgbImage colourize_depth(const DepthImage& depth, float near_m, float far_m) {
  // A five-stop ramp: red, yellow, green, cyan, blue.
  static constexpr std::array<std::array<float, 3>, 5> stops = {
      {{220, 40, 30}, {240, 210, 40}, {60, 200, 80}, {40, 190, 210}, {40, 70, 200}}};
  RgbImage out(depth.width, depth.height);
  const float span = std::max(far_m - near_m, 1e-6f);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const float z = depth.at(u, v);
      if (!std::isfinite(z)) continue;
      const float t = std::clamp((z - near_m) / span, 0.0f, 1.0f) * 4.0f;
      const int k = std::min(static_cast<int>(t), 3);
      const float f = t - static_cast<float>(k);
      const auto& a = stops[static_cast<std::size_t>(k)];
      const auto& b = stops[static_cast<std::size_t>(k) + 1];
      out.set(u, v, static_cast<std::uint8_t>(a[0] + f * (b[0] - a[0])), static_cast<std::uint8_t>(a[1] + f * (b[1] - a[1])),
              static_cast<std::uint8_t>(a[2] + f * (b[2] - a[2])));
    }
  }
  return out;
}

void draw_line(RgbImage& image, Eigen::Vector2d a, Eigen::Vector2d b, const std::array<std::uint8_t, 3>& c) {
  const double length = (b - a).norm();
  if (!std::isfinite(length)) return;
  const int steps = std::max(1, static_cast<int>(std::ceil(length)));
  for (int i = 0; i <= steps && i <= 100000; ++i) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(i) / steps);
    for (int d = 0; d < 2; ++d) image.set(static_cast<int>(std::lround(p.x())) + d, static_cast<int>(std::lround(p.y())), c[0], c[1], c[2]);
  }
}

std::array<std::uint8_t, 3> palette(std::size_t i) {
  static constexpr std::array<std::array<std::uint8_t, 3>, 8> colours = {
      {{255, 64, 160}, {64, 255, 255}, {255, 200, 0}, {160, 100, 255}, {0, 255, 100}, {255, 120, 40}, {255, 255, 255}, {120, 160, 255}}};
  return colours[i % colours.size()];
}

RgbImage tile_images(std::span<const RgbImage> images, int columns, int gap) {
  if (images.empty() || columns <= 0) return {};
  int cell_w = 0, cell_h = 0;
  for (const auto& im : images) {
    cell_w = std::max(cell_w, im.width);
    cell_h = std::max(cell_h, im.height);
  }
  const int n = static_cast<int>(images.size());
  const int cols = std::min(columns, n), rows = (n + cols - 1) / cols;
  RgbImage sheet(gap + cols * (cell_w + gap), gap + rows * (cell_h + gap), 96);
  for (int i = 0; i < n; ++i) {
    const RgbImage& im = images[static_cast<std::size_t>(i)];
    const int x0 = gap + (i % cols) * (cell_w + gap), y0 = gap + (i / cols) * (cell_h + gap);
    for (int v = 0; v < im.height; ++v) {
      std::copy_n(im.rgb.begin() + 3 * static_cast<std::ptrdiff_t>(v) * im.width, 3 * im.width,
                  sheet.rgb.begin() + 3 * (static_cast<std::ptrdiff_t>(y0 + v) * sheet.width + x0));
    }
  }
  return sheet;
}

}  // namespace viewpose
