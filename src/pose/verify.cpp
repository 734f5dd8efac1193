#include "viewpose/pose/verify.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Eigenvalues>

#include "viewpose/core/point_cloud.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/sensor_model.hpp"

namespace viewpose {

namespace {

// The pixel a projected coordinate falls in, as std::lround, without its library call (a
// tenth of verification's time was spent there).
int nearest_pixel(double x) { return x >= 0 ? static_cast<int>(x + 0.5) : -static_cast<int>(0.5 - x); }

}  // namespace

float depth_noise_tolerance(float z_m, const VerifyOptions& o) {
  return o.base_tolerance_m + o.noise_factor * axial_noise_sigma_frontal(z_m);
}

float depth_tolerance(float z_m, const VerifyOptions& o) { return std::min(o.max_tolerance_m, depth_noise_tolerance(z_m, o)); }

namespace {

// Sums for a least-squares plane through points: RMS distance from the best plane at the end.
// Scalar moments (the six distinct products): this runs for every inlier pixel, twice.
struct PlaneSums {
  double n = 0, x = 0, y = 0, z = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  void add(double px, double py, double pz) {
    n += 1;
    x += px, y += py, z += pz;
    xx += px * px, xy += px * py, xz += px * pz, yy += py * py, yz += py * pz, zz += pz * pz;
  }
  double rms_distance() const {
    if (n < 3) return 0;
    const Eigen::Vector3d mean(x / n, y / n, z / n);
    Eigen::Matrix3d cov;
    cov << xx / n, xy / n, xz / n, xy / n, yy / n, yz / n, xz / n, yz / n, zz / n;
    cov -= mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov, Eigen::EigenvaluesOnly);
    return std::sqrt(std::max(0.0, eig.eigenvalues()(0)));
  }
};

}  // namespace

namespace {

// The pixels the model is judged on: the window [u0, u1) x [v0, v1) its bounding box projects to,
// plus a margin for the edge test, which may reach up to `kBorder` pixels beyond the image on every
// side (whatever of the model falls outside the image counts as unseen rather than not existing;
// pixels outside the window hold no model and need no look), sampled every `step` pixels.
struct JudgedWindow {
  static constexpr int kBorder = 64;
  int u0 = 0, v0 = 0, u1 = 0, v1 = 0;
  int step = 1;
  CameraIntrinsics Kx;  // the camera on the samples: sample (xs, ys) is pixel (u0 + s xs, v0 + s ys)
};

JudgedWindow judged_window(const VerifyModel& shape, const Transform& T_camera_object, const CameraIntrinsics& K,
                           const VerifyOptions& o) {
  const int W = K.width, H = K.height, m = std::max(0, o.edge_margin_px), border = JudgedWindow::kBorder;
  JudgedWindow w;
  w.u0 = -border, w.v0 = -border, w.u1 = W + border, w.v1 = H + border;
  // (No copy of a scanned model's points for it: this runs once per hypothesis.)
  const BoundingBox box = shape.mesh && !shape.mesh->triangles.empty() ? bounding_box(*shape.mesh) : bounding_box(shape.points);
  double lo_u = 1e9, lo_v = 1e9, hi_u = -1e9, hi_v = -1e9;
  bool in_front = !box.empty;
  for (int corner = 0; corner < 8 && in_front; ++corner) {
    const Eigen::Vector3d p(corner & 1 ? box.max.x() : box.min.x(), corner & 2 ? box.max.y() : box.min.y(),
                            corner & 4 ? box.max.z() : box.min.z());
    const Eigen::Vector3d c = T_camera_object * p;
    in_front = c.z() > 1e-6;
    const Eigen::Vector2d uv = K.project(c);
    lo_u = std::min(lo_u, uv.x()), hi_u = std::max(hi_u, uv.x());
    lo_v = std::min(lo_v, uv.y()), hi_v = std::max(hi_v, uv.y());
  }
  // A box reaching behind the camera projects to no window: draw the whole frame.
  if (in_front) {
    const int pad = m + 2;
    w.u0 = std::clamp(static_cast<int>(std::floor(lo_u)) - pad, -border, W + border);
    w.v0 = std::clamp(static_cast<int>(std::floor(lo_v)) - pad, -border, H + border);
    w.u1 = std::clamp(static_cast<int>(std::ceil(hi_u)) + pad + 1, w.u0, W + border);
    w.v1 = std::clamp(static_cast<int>(std::ceil(hi_v)) + pad + 1, w.v0, H + border);
  }
  // The step s between judged pixels: 1 unless the window is larger than the pixel budget.
  const double window_pixels = static_cast<double>(w.u1 - w.u0) * static_cast<double>(w.v1 - w.v0);
  const double budget = static_cast<double>(std::max<std::size_t>(1, o.max_judged_pixels));
  w.step = std::max(1, static_cast<int>(std::ceil(std::sqrt(window_pixels / budget))));
  w.Kx = K;
  w.Kx.width = std::max(1, (w.u1 - w.u0 + w.step - 1) / w.step);
  w.Kx.height = std::max(1, (w.v1 - w.v0 + w.step - 1) / w.step);
  w.Kx.fx /= w.step;
  w.Kx.fy /= w.step;
  w.Kx.cx = (K.cx - w.u0) / w.step;
  w.Kx.cy = (K.cy - w.v0) / w.step;
  return w;
}

// The model drawn on the window's samples.
RenderedFrame draw_model(const VerifyModel& shape, const Transform& T_camera_object, const JudgedWindow& w) {
  if (shape.mesh && !shape.mesh->triangles.empty()) {
    const MeshInstance inst{shape.mesh, T_camera_object};
    RenderOptions options;
    options.closed_winding = shape.closed_winding;
    options.instances = false;
    return render(std::span(&inst, 1), w.Kx, options);
  }
  return render_points(shape.points, T_camera_object, w.Kx, shape.point_spacing_m);
}

// The camera pixels the cluster covers within the window (and the image), each of its points
// splatted over its voxel's footprint.
class ClusterMask {
 public:
  ClusterMask(std::span<const Eigen::Vector3f> cluster_points, const CameraIntrinsics& K, const JudgedWindow& w,
              float point_spacing_m)
      : u0_(std::max(w.u0, 0)), v0_(std::max(w.v0, 0)),
        width_(std::max(0, std::min(w.u1, K.width) - u0_)), height_(std::max(0, std::min(w.v1, K.height) - v0_)),
        mask_(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0) {
    for (const Eigen::Vector3f& p : cluster_points) {
      if (!p.allFinite() || !(p.z() > 0)) continue;
      const Eigen::Vector2d uv = K.project(p.cast<double>());
      const int half = std::max(1, static_cast<int>(std::ceil(0.5 * K.fx * point_spacing_m / p.z())));
      const int cu = nearest_pixel(uv.x()), cv = nearest_pixel(uv.y());
      for (int y = std::max(v0_, cv - half); y <= std::min(v0_ + height_ - 1, cv + half); ++y)
        for (int x = std::max(u0_, cu - half); x <= std::min(u0_ + width_ - 1, cu + half); ++x) at(x, y) = 1;
    }
  }
  // (x, y) is a pixel of the image inside the window.
  bool covers(int x, int y) const { return mask_[index(x, y)] != 0; }

 private:
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y - v0_) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x - u0_);
  }
  char& at(int x, int y) { return mask_[index(x, y)]; }
  int u0_, v0_, width_, height_;
  std::vector<char> mask_;
};

// What the judgement of the model's interior pixels sums, beside the Verification's counts.
struct InteriorSums {
  std::size_t supported = 0;  // inliers the cluster covers
  double depth_sum = 0;
  std::size_t depth_count = 0;
  PlaneSums observed_plane, model_plane;
  double model_sq = 0;
};

// Each sample well inside the model's outline and away from its own depth steps, against the
// observed depth there: inlier, conflict (the scene lies behind the model: it would be seen
// through), occluded (something in front), or unmeasured. Counts in samples.
InteriorSums judge_interior(const RenderedFrame& model, const JudgedWindow& w, const DepthImage& observed,
                            const CameraIntrinsics& K, const ClusterMask& cluster, int ms, const VerifyOptions& o,
                            Verification& v) {
  InteriorSums sums;
  const int W = K.width, H = K.height, step = w.step, stride = w.Kx.width;
  const double inv_fx = 1.0 / K.fx, inv_fy = 1.0 / K.fy;
  for (int ys = ms; ys < w.Kx.height - ms; ++ys) {
    const int y = w.v0 + ys * step;
    const float* row = model.depth.depth_m.data() + static_cast<std::ptrdiff_t>(ys) * stride;
    const float* up = row - static_cast<std::ptrdiff_t>(ms) * stride;
    const float* down = row + static_cast<std::ptrdiff_t>(ms) * stride;
    const bool row_in_image = y >= 0 && y < H;
    for (int xs = ms; xs < w.Kx.width - ms; ++xs) {
      const float zm = row[xs];
      if (!std::isfinite(zm)) continue;
      const float tol = depth_tolerance(zm, o);
      // Only pixels well inside the model's outline and away from its own depth steps are judged:
      // edges are where the sensor's lateral noise lives. (A NaN neighbour fails the test.)
      if (!(std::abs(row[xs + ms] - zm) <= tol && std::abs(row[xs - ms] - zm) <= tol && std::abs(up[xs] - zm) <= tol &&
            std::abs(down[xs] - zm) <= tol))
        continue;
      const int x = w.u0 + xs * step;
      if (!row_in_image || x < 0 || x >= W) {
        ++v.unknown;  // outside the image: not seen
        continue;
      }
      const float zo = observed.at(x, y);
      const bool cluster_here = cluster.covers(x, y);
      if (!std::isfinite(zo)) ++v.unknown;
      else if (zo < zm - tol) {
        // Something in front hides the model here. If that something is the cluster the model is
        // meant to be, the pose puts the object behind its own surface (a can sunk into a keyboard
        // with its lid flush): evidence against, not occlusion.
        if (cluster_here && o.cluster_cannot_hide_model) ++v.hidden_by_cluster;
        else ++v.occluded;
      } else if (zo > zm + tol) ++v.conflicts;
      else {
        ++v.inliers;
        sums.supported += cluster_here;
        const double rx = (x - K.cx) * inv_fx, ry = (y - K.cy) * inv_fy;
        sums.observed_plane.add(rx * zo, ry * zo, zo);
        sums.model_plane.add(rx * zm, ry * zm, zm);
        sums.model_sq += static_cast<double>(zo - zm) * static_cast<double>(zo - zm);
      }
      sums.depth_sum += zm;
      ++sums.depth_count;
    }
  }
  return sums;
}

// The outline, in a pass of its own (inside the interior loop it slowed every pixel's judgement): a
// sample whose neighbour ms away has no model is on the silhouette; look `reach_out` camera pixels
// beyond it, outward: does the scene step away there, lie in front, or carry on at the model's depth?
void judge_outline(const RenderedFrame& model, const JudgedWindow& w, const DepthImage& observed, const CameraIntrinsics& K,
                   int ms, int reach_out, const VerifyOptions& o, Verification& v) {
  const int W = K.width, H = K.height, stride = w.Kx.width;
  const auto look = [&](int x, int y, float z_edge, float tol) {
    if (x < 0 || y < 0 || x >= W || y >= H) return;
    const float zo = observed.at(x, y);
    if (!std::isfinite(zo)) ++v.outline_unknown;
    else if (zo > z_edge + tol) ++v.outline_stepped;
    else if (zo < z_edge - tol) ++v.outline_in_front;
    else ++v.outline_continued;
  };
  for (int ys = ms; ys < w.Kx.height - ms; ++ys) {
    const int y = w.v0 + ys * w.step;
    const float* row = model.depth.depth_m.data() + static_cast<std::ptrdiff_t>(ys) * stride;
    const float* up = row - static_cast<std::ptrdiff_t>(ms) * stride;
    const float* down = row + static_cast<std::ptrdiff_t>(ms) * stride;
    for (int xs = ms; xs < w.Kx.width - ms; ++xs) {
      const float zm = row[xs];
      if (!std::isfinite(zm)) continue;
      const bool right = std::isfinite(row[xs + ms]), left = std::isfinite(row[xs - ms]);
      const bool below = std::isfinite(down[xs]), above = std::isfinite(up[xs]);
      if (right && left && below && above) continue;
      const float tol = depth_tolerance(zm, o);
      const int x = w.u0 + xs * w.step;
      if (!right) look(x + reach_out, y, zm, tol);
      if (!left) look(x - reach_out, y, zm, tol);
      if (!below) look(x, y + reach_out, zm, tol);
      if (!above) look(x, y - reach_out, zm, tol);
    }
  }
}

// The other way round: the share of the cluster's points that lie on the model's surface (within
// the depth tolerance and a pixel).
void explained_share(std::span<const Eigen::Vector3f> cluster_points, const RenderedFrame& model, const JudgedWindow& w,
                     const CameraIntrinsics& K, const VerifyOptions& o, Verification& v) {
  const auto z_sample = [&](int xs, int ys) -> float {
    return (xs < 0 || ys < 0 || xs >= w.Kx.width || ys >= w.Kx.height) ? NAN : model.depth.at(xs, ys);
  };
  std::size_t explained = 0, counted = 0, beside = 0;
  // Beyond this many camera pixels of the model's silhouette a point is beside the object.
  const int near = std::max(1, (o.beside_margin_px + w.step - 1) / w.step);
  for (const Eigen::Vector3f& p : cluster_points) {
    if (!p.allFinite() || !(p.z() > 0)) continue;
    ++counted;
    const Eigen::Vector2d uv = K.project(p.cast<double>());
    // The pixels within one of the point's; where every s-th pixel is drawn, the samples within one
    // (s = 2: two pixels), or from s = 3 on the nearest sample only (within s/2 pixels): the
    // neighbours of a sample would reach s pixels and more, and explain poses that are off.
    const int us = nearest_pixel((uv.x() - w.u0) / w.step), ws = nearest_pixel((uv.y() - w.v0) / w.step);
    const float tol = depth_tolerance(p.z(), o);
    const int reach = w.step <= 2 ? 1 : 0;
    bool hit = false;
    for (int dv = -reach; dv <= reach && !hit; ++dv)
      for (int du = -reach; du <= reach && !hit; ++du) {
        const float zm = z_sample(us + du, ws + dv);
        hit = std::isfinite(zm) && std::abs(zm - p.z()) <= tol;
      }
    explained += hit ? 1 : 0;
    if (!hit) {
      // Drawn within `near` samples? Only the samples inside the window are looked at: most points
      // beside the model lie far outside it, and cost no look-up at all.
      bool drawn = false;
      const int u_lo = std::max(us - near, 0), u_hi = std::min(us + near, w.Kx.width - 1);
      const int v_lo = std::max(ws - near, 0), v_hi = std::min(ws + near, w.Kx.height - 1);
      for (int vs = v_lo; vs <= v_hi && !drawn; ++vs)
        for (int u = u_lo; u <= u_hi && !drawn; ++u) drawn = std::isfinite(model.depth.at(u, vs));
      beside += drawn ? 0 : 1;
    }
  }
  v.cluster_explained = counted ? static_cast<double>(explained) / static_cast<double>(counted) : 0.0;
  v.cluster_beside = counted ? static_cast<double>(beside) / static_cast<double>(counted) : 0.0;
  v.footprint_explained = counted > beside ? static_cast<double>(explained) / static_cast<double>(counted - beside) : 0.0;
}

// The counts (in samples) scaled to camera pixels, and the fractions the verdict is made of.
void summarize(const InteriorSums& sums, int step, Verification& v) {
  v.mean_depth_m = sums.depth_count ? sums.depth_sum / static_cast<double>(sums.depth_count) : 0.0;
  v.model_rms_m = sums.observed_plane.n > 0 ? std::sqrt(sums.model_sq / sums.observed_plane.n) : 0.0;
  v.plane_rms_m = sums.observed_plane.rms_distance();
  v.model_relief_m = sums.model_plane.rms_distance();
  const std::size_t outline_judged = v.outline_continued + v.outline_stepped;
  v.outline_continuation = outline_judged ? static_cast<double>(v.outline_continued) / static_cast<double>(outline_judged) : 0.0;
  // Each sample stands for s x s camera pixels.
  const std::size_t area = static_cast<std::size_t>(step) * static_cast<std::size_t>(step);
  v.inliers *= area, v.conflicts *= area, v.occluded *= area, v.unknown *= area, v.hidden_by_cluster *= area;
  const std::size_t supported = sums.supported * area;
  const std::size_t judged = v.inliers + v.conflicts + v.hidden_by_cluster;
  v.inlier_fraction = judged ? static_cast<double>(v.inliers) / static_cast<double>(judged) : 0.0;
  const std::size_t all = judged + v.occluded + v.unknown;
  v.visible_fraction = all ? static_cast<double>(v.inliers) / static_cast<double>(all) : 0.0;
  const std::size_t unhidden = judged + v.unknown;
  v.unmeasured_fraction = unhidden ? static_cast<double>(v.unknown) / static_cast<double>(unhidden) : 0.0;
  v.model_support = v.inliers ? static_cast<double>(supported) / static_cast<double>(v.inliers) : 0.0;
  v.conflict_fraction = judged ? static_cast<double>(v.conflicts + v.hidden_by_cluster) / static_cast<double>(judged) : 0.0;
}

}  // namespace

SeenThrough seen_through(std::span<const Eigen::Vector3f> points, std::span<const Eigen::Vector3f> normals, const Transform& T_camera_object, const DepthImage& observed,
                         const CameraIntrinsics& K, const VerifyOptions& o, std::size_t max_points) {
  SeenThrough s;
  if (points.empty() || max_points == 0 || observed.width != K.width || observed.height != K.height) return s;
  const std::size_t n = std::min(points.size(), max_points);
  const Eigen::Matrix3f R = T_camera_object.linear().cast<float>();
  const Eigen::Vector3f t = T_camera_object.translation().cast<float>();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t at = points.size() * k / n;
    const Eigen::Vector3f p = R * points[at] + t;
    if (!(p.z() > 0)) continue;
    // A point whose surface the line of sight grazes lies at the model's outline, where a pixel's
    // error reads as seen through; the full test leaves its outline out too. (Cosine 0.5: 60 degrees.)
    if (normals.size() == points.size() && std::abs((R * normals[at]).dot(p)) < 0.5f * p.norm()) continue;
    const float u = static_cast<float>(K.fx) * p.x() / p.z() + static_cast<float>(K.cx);
    const float v = static_cast<float>(K.fy) * p.y() / p.z() + static_cast<float>(K.cy);
    // Nearest pixel centre; outside the image (NaN included) nothing is judged.
    if (!(u > -0.5f && v > -0.5f && u < static_cast<float>(K.width) - 0.5f && v < static_cast<float>(K.height) - 0.5f)) continue;
    const int iu = static_cast<int>(u + 0.5f), iv = static_cast<int>(v + 0.5f);
    const float z = observed.at(iu, iv);
    if (!std::isfinite(z)) continue;
    const float tolerance = depth_tolerance(p.z(), o);
    if (z < p.z() - tolerance) continue;  // something in front: hidden, not judged
    ++s.judged;
    if (z > p.z() + tolerance) ++s.seen_through;
  }
  return s;
}

std::optional<double> seen_through_quickly(const VerifyModel& shape, const Transform& T_camera_object, const DepthImage& observed,
                                           const CameraIntrinsics& K, const VerifyOptions& o) {
  if (!(o.quick_max_seen_through < 1)) return std::nullopt;
  const SeenThrough quick = seen_through(shape.points, shape.normals, T_camera_object, observed, K, o, o.quick_points);
  if (quick.judged >= o.quick_min_judged && quick.fraction() > o.quick_max_seen_through) return quick.fraction();
  return std::nullopt;
}

Verification verify_pose(const VerifyModel& shape, const Transform& T_camera_object, const DepthImage& observed,
                         const CameraIntrinsics& K, std::span<const Eigen::Vector3f> cluster_points,
                         const VerifyOptions& o) {
  Verification v;
  if (const std::optional<double> share = seen_through_quickly(shape, T_camera_object, observed, K, o)) {
    v.refused_quickly = true;
    v.conflict_fraction = *share;
    v.inlier_fraction = 1 - *share;
    return v;
  }
  const JudgedWindow w = judged_window(shape, T_camera_object, K, o);
  v.pixel_step = w.step;
  const RenderedFrame model = draw_model(shape, T_camera_object, w);
  const ClusterMask cluster(cluster_points, K, w, shape.point_spacing_m);
  // A sample within ms of the window's edge has a neighbour ms away outside the window, where the
  // model is not drawn: it cannot be interior. So only the inner window is judged, and its
  // neighbours are read without bounds checks. (The edge test's reach stays at least m camera pixels.)
  const int m = std::max(0, o.edge_margin_px), step = w.step;
  const int ms = step == 1 ? m : std::max(1, (m + step - 1) / step);
  const InteriorSums sums = judge_interior(model, w, observed, K, cluster, ms, o, v);
  // The outline is looked at this many camera pixels beyond the edge: past the sensor's lateral
  // jitter (about a pixel) and the edge margin.
  const int reach_out = std::max(m + 3, (ms + 1) * step + 1);
  judge_outline(model, w, observed, K, ms, reach_out, o, v);
  summarize(sums, step, v);
  explained_share(cluster_points, model, w, K, o, v);
  v.score = v.inlier_fraction * v.cluster_explained;
  v.explained_beside_neighbour = explained_beside_neighbour(v, o);
  v.accepted = passes(v, o);
  return v;
}

bool explained_beside_neighbour(const Verification& v, const VerifyOptions& o) {
  return v.cluster_explained < o.min_cluster_explained && o.min_footprint_explained > 0 &&
         v.footprint_explained >= std::max(o.min_footprint_explained, o.min_cluster_explained) &&
         v.cluster_explained >= o.min_cluster_explained_beside && v.outline_continuation <= o.max_beside_outline_continuation;
}

bool passes(const Verification& v, const VerifyOptions& o) {
  const bool flat = v.model_relief_m < o.flat_relief_sigmas * axial_noise_sigma_frontal(std::max(0.3, v.mean_depth_m));
  if (flat && v.outline_continuation > o.max_flat_outline_continuation) return false;
  return v.inliers >= o.min_inliers && v.inlier_fraction >= o.min_inlier_fraction &&
         v.conflict_fraction <= o.max_conflict_fraction &&
         (v.cluster_explained >= o.min_cluster_explained || explained_beside_neighbour(v, o)) &&
         v.model_support >= o.min_model_support && v.visible_fraction >= o.min_visible_fraction &&
         v.unmeasured_fraction <= o.max_unmeasured_fraction && v.mean_depth_m <= o.max_depth_m;
}

}  // namespace viewpose
