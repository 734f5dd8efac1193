#pragma once
// What a Kinect v1 / Xtion (structured light) does to a perfect depth frame. Each effect can be
// switched off; docs/SENSOR_MODEL.md gives the numbers and their sources. Deterministic: the same
// frame and seed give the same output, whatever the thread count.
#include <cstdint>

#include "viewpose/core/camera.hpp"
#include "viewpose/core/depth_image.hpp"
#include "viewpose/render/rasterizer.hpp"

namespace viewpose {

struct SensorModel {
  double baseline_m = 0.075;  ///< IR projector to IR camera, along +x (Khoshelham & Elberink 2012)
  bool quantize = true;       ///< depth through disparity quantized to 1/8 pixel
  double disparity_step_px = 0.125;
  bool axial_noise = true;    ///< Gaussian depth noise, sigma of Nguyen, Izadi & Lovell 2012
  bool lateral_noise = true;  ///< each pixel samples a neighbour ~N(0, sigma_L) pixels away: edges jitter
  bool shadows = true;        ///< surface the projector cannot light returns nothing
  bool grazing_dropout = true;  ///< no return at grazing incidence, ramping between these angles
  double grazing_start_deg = 70.0;
  double grazing_end_deg = 85.0;
  bool random_dropout = true;  ///< isolated missing pixels
  double dropout_probability = 0.002;
  bool range_limits = true;
  double min_range_m = 0.5;
  double max_range_m = 4.5;

  /// Every effect off: the rendered depth passes through unchanged.
  static SensorModel ideal();
  /// Kinect v1 / Xtion defaults (the values above).
  static SensorModel kinect_v1() { return {}; }
};

/// Standard deviation (m) of a Kinect v1's depth at depth z (m) and incidence angle theta (rad)
/// between the surface normal and the viewing ray: Nguyen et al. 2012, eq. 2, including the
/// disparity quantization of the device they measured.
double axial_noise_sigma(double z_m, double theta_rad);
/// Its first term, all there is for a surface facing the sensor (theta = 0); inline, as
/// verification asks for it at every pixel.
template <typename Real>
inline Real axial_noise_sigma_frontal(Real z_m) {
  return Real(0.0012) + Real(0.0019) * (z_m - Real(0.4)) * (z_m - Real(0.4));
}

/// Lateral noise (pixels) at incidence theta: Nguyen et al. 2012, 0.8 + 0.035 theta / (pi/2 - theta).
double lateral_noise_sigma_px(double theta_rad);

/// Depth step (m) between neighbouring disparity levels at depth z for focal length fx (pixels).
double quantization_step(double z_m, double fx, const SensorModel& model);

/// The frame as the sensor would report it. Needs the frame's normals (render with normals = true)
/// for the effects that depend on the incidence angle.
DepthImage simulate_sensor(const RenderedFrame& frame, const CameraIntrinsics& K, const SensorModel& model,
                           std::uint64_t seed);

}  // namespace viewpose
