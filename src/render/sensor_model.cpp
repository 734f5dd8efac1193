#include "viewpose/render/sensor_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <fmt/format.h>

#include "viewpose/core/threads.hpp"
#include "viewpose/core/error.hpp"

namespace viewpose {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// An independent random stream per (seed, effect, row): the output does not depend on which thread
// handles which row.
std::mt19937_64 row_stream(std::uint64_t seed, std::uint64_t effect, int row) {
  std::uint64_t x = seed ^ (effect * 0x9E3779B97F4A7C15ull) ^ (static_cast<std::uint64_t>(row) * 0xBF58476D1CE4E5B9ull);
  // splitmix64 finaliser: nearby seeds give unrelated streams
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return std::mt19937_64(x ^ (x >> 31));
}

// Incidence angle between the surface normal and the ray to the camera, per pixel.
std::vector<float> incidence_angles(const RenderedFrame& frame, const CameraIntrinsics& K) {
  std::vector<float> theta(frame.depth.depth_m.size(), 0.0f);
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(K.width) + static_cast<std::size_t>(u);
      const Eigen::Vector3f ray = K.unproject(u, v, 1.0).cast<float>().normalized();
      const float c = std::clamp(-frame.normal[i].dot(ray), 0.0f, 1.0f);
      theta[i] = std::acos(c);
    }
  }
  return theta;
}

std::size_t index(const CameraIntrinsics& K, int u, int v) {
  return static_cast<std::size_t>(v) * static_cast<std::size_t>(K.width) + static_cast<std::size_t>(u);
}

// Marks pixels the projector (at +baseline along x) cannot light. The projector shares the
// camera's rows (it is displaced along x only), so each row is an independent 1-D z-buffer over
// projector columns u_p = u - fx * b / z.
void cast_shadows(DepthImage& depth, const CameraIntrinsics& K, double baseline) {
  const int W = K.width;
  FirstException failed;
#pragma omp parallel
  {
    // Each thread's rows of the projector's view (allocated in failed.run: a thread without them
    // runs no row).
    std::vector<float> zbuf;
    std::vector<double> up;
    failed.run(-1, [&] {
      zbuf.resize(static_cast<std::size_t>(W));
      up.resize(static_cast<std::size_t>(W));
    });
#pragma omp for
    for (int v = 0; v < K.height; ++v) {
      failed.run(v, [&] {
        std::fill(zbuf.begin(), zbuf.end(), std::numeric_limits<float>::infinity());
        const auto put = [&](int col, float z) {
          if (col >= 0 && col < W) zbuf[static_cast<std::size_t>(col)] = std::min(zbuf[static_cast<std::size_t>(col)], z);
        };
        for (int u = 0; u < W; ++u) {
          const float z = depth.at(u, v);
          up[static_cast<std::size_t>(u)] = std::isfinite(z) ? u - K.fx * baseline / z : NAN;
          if (std::isfinite(z)) put(static_cast<int>(std::lround(up[static_cast<std::size_t>(u)])), z);
        }
        // Fill the projector columns between neighbouring pixels of one surface, so that a near
        // surface's shadow has no gaps.
        for (int u = 0; u + 1 < W; ++u) {
          const float za = depth.at(u, v), zb = depth.at(u + 1, v);
          if (!std::isfinite(za) || !std::isfinite(zb) || std::abs(za - zb) > 0.02f * std::min(za, zb) + 0.005f) continue;
          const double ua = up[static_cast<std::size_t>(u)], ub = up[static_cast<std::size_t>(u) + 1];
          for (int c = static_cast<int>(std::ceil(std::min(ua, ub))); c <= static_cast<int>(std::floor(std::max(ua, ub))); ++c) {
            const double t = ub == ua ? 0.0 : (c - ua) / (ub - ua);
            put(c, static_cast<float>(za + t * (zb - za)));
          }
        }
        for (int u = 0; u < W; ++u) {
          float& z = depth.at(u, v);
          if (!std::isfinite(z)) continue;
          const int c = static_cast<int>(std::lround(up[static_cast<std::size_t>(u)]));
          if (c >= 0 && c < W && z > zbuf[static_cast<std::size_t>(c)] + 0.01f * z + 0.005f) z = kNaN;
        }
      });
    }
  }
  failed.rethrow();
}

}  // namespace

SensorModel SensorModel::ideal() {
  SensorModel m;
  m.quantize = m.axial_noise = m.lateral_noise = m.shadows = m.grazing_dropout = m.random_dropout = m.range_limits = false;
  return m;
}

double axial_noise_sigma(double z_m, double theta_rad) {
  const double t = std::min(theta_rad, std::numbers::pi / 2 - 0.01);
  return axial_noise_sigma_frontal(z_m) +
         0.0001 / std::sqrt(z_m) * t * t / ((std::numbers::pi / 2 - t) * (std::numbers::pi / 2 - t));
}

double lateral_noise_sigma_px(double theta_rad) {
  const double t = std::min(theta_rad, std::numbers::pi / 2 - 0.01);
  return 0.8 + 0.035 * t / (std::numbers::pi / 2 - t);
}

double quantization_step(double z_m, double fx, const SensorModel& model) {
  return z_m * z_m * model.disparity_step_px / (fx * model.baseline_m);
}

DepthImage simulate_sensor(const RenderedFrame& frame, const CameraIntrinsics& K, const SensorModel& model,
                           std::uint64_t seed) {
  K.validate();
  if (frame.depth.width != K.width || frame.depth.height != K.height) {
    throw Error(fmt::format("sensor model: frame is {}x{} but the camera is {}x{}", frame.depth.width,
                            frame.depth.height, K.width, K.height));
  }
  const bool needs_normals = model.axial_noise || model.lateral_noise || model.grazing_dropout;
  if (needs_normals && frame.normal.size() != frame.depth.depth_m.size()) {
    throw Error("sensor model: the frame has no normals (render with normals = true)");
  }
  const std::vector<float> theta = needs_normals ? incidence_angles(frame, K) : std::vector<float>();
  DepthImage depth = frame.depth;

  if (model.lateral_noise) {
    const DepthImage before = depth;
#pragma omp parallel for
    for (int v = 0; v < K.height; ++v) {
      auto rng = row_stream(seed, 1, v);
      std::normal_distribution<double> unit(0.0, 1.0);
      for (int u = 0; u < K.width; ++u) {
        const double s = lateral_noise_sigma_px(theta[index(K, u, v)]);
        const int su = std::clamp(u + static_cast<int>(std::lround(s * unit(rng))), 0, K.width - 1);
        const int sv = std::clamp(v + static_cast<int>(std::lround(s * unit(rng))), 0, K.height - 1);
        depth.at(u, v) = before.at(su, sv);
      }
    }
  }
  if (model.shadows) cast_shadows(depth, K, model.baseline_m);

  const double start = model.grazing_start_deg * std::numbers::pi / 180, end = model.grazing_end_deg * std::numbers::pi / 180;
#pragma omp parallel for
  for (int v = 0; v < K.height; ++v) {
    auto rng = row_stream(seed, 2, v);
    std::normal_distribution<double> unit(0.0, 1.0);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (int u = 0; u < K.width; ++u) {
      float& z = depth.at(u, v);
      // Draw every number for every pixel, valid or not, so streams stay aligned between runs.
      const double g = unit(rng), p_graze = uniform(rng), p_drop = uniform(rng);
      if (!std::isfinite(z)) continue;
      const double t = needs_normals ? theta[index(K, u, v)] : 0.0;
      if (model.grazing_dropout && t > start && p_graze < std::min(1.0, (t - start) / std::max(end - start, 1e-9))) {
        z = kNaN;
        continue;
      }
      double zn = z;
      if (model.axial_noise) {
        // Nguyen's sigma was measured on quantized output: add only what quantization does not.
        const double total = axial_noise_sigma(zn, t);
        const double q = model.quantize ? quantization_step(zn, K.fx, model) : 0.0;
        zn += std::sqrt(std::max(0.0, total * total - q * q / 12.0)) * g;
      }
      if (model.quantize && zn > 0) {
        const double disparity = K.fx * model.baseline_m / zn;
        zn = K.fx * model.baseline_m / (std::round(disparity / model.disparity_step_px) * model.disparity_step_px);
      }
      if (model.range_limits && !(zn >= model.min_range_m && zn <= model.max_range_m)) zn = NAN;
      if (model.random_dropout && p_drop < model.dropout_probability) zn = NAN;
      z = static_cast<float>(zn);
    }
  }
  return depth;
}

}  // namespace viewpose
