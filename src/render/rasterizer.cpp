#include "viewpose/render/rasterizer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "viewpose/core/threads.hpp"
#include "viewpose/core/error.hpp"

namespace viewpose {

namespace {

// A camera-frame vertex with its image coordinates and inverse depth.
struct ProjectedVertex {
  Eigen::Vector3d p;
  double su = 0, sv = 0, inv_z = 0;
};

ProjectedVertex project(const CameraIntrinsics& K, const Eigen::Vector3d& p) {
  ProjectedVertex v;
  v.p = p;
  v.inv_z = 1.0 / p.z();
  v.su = K.fx * p.x() * v.inv_z + K.cx;
  v.sv = K.fy * p.y() * v.inv_z + K.cy;
  return v;
}

// Rasterizes one camera-frame triangle (all vertices in front of the near plane) into the frame.
class TriangleRasterizer {
 public:
  TriangleRasterizer(const CameraIntrinsics& K, RenderedFrame& frame, bool normals, bool instances, int closed_winding)
      : K_(K), frame_(frame), normals_(normals), instances_(instances), closed_winding_(closed_winding) {}

  void draw(const ProjectedVertex& a, const ProjectedVertex& b, const ProjectedVertex& c, std::int32_t instance) {
    const std::array<Eigen::Vector3d, 3> p = {a.p, b.p, c.p};
    const std::array<double, 3> su = {a.su, b.su, c.su}, sv = {a.sv, b.sv, c.sv}, inv_z = {a.inv_z, b.inv_z, c.inv_z};
    // Twice the signed area in pixels; degenerate (edge-on) triangles cover no pixel centre.
    const double area = (su[1] - su[0]) * (sv[2] - sv[0]) - (sv[1] - sv[0]) * (su[2] - su[0]);
    if (!(std::abs(area) > 1e-12)) return;
    // Seen from outside, a counter-clockwise face turns clockwise in the image (v runs down), so
    // its signed area is negative: a face of the other sign shows its back.
    if (closed_winding_ != 0 && area * closed_winding_ > 0) return;
    const int u0 = std::max(0, static_cast<int>(std::ceil(std::min({su[0], su[1], su[2]}))));
    const int u1 = std::min(K_.width - 1, static_cast<int>(std::floor(std::max({su[0], su[1], su[2]}))));
    const int v0 = std::max(0, static_cast<int>(std::ceil(std::min({sv[0], sv[1], sv[2]}))));
    const int v1 = std::min(K_.height - 1, static_cast<int>(std::floor(std::max({sv[0], sv[1], sv[2]}))));
    if (u0 > u1 || v0 > v1) return;
    Eigen::Vector3f n = Eigen::Vector3f::Zero();
    if (normals_) {
      Eigen::Vector3d nd = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
      if (nd.dot(p[0]) > 0) nd = -nd;  // face the camera
      n = nd.cast<float>();
    }
    // Edge functions e_i(u, v) = A_i u + B_i v + C_i, positive inside for a counter-clockwise
    // triangle; divided by the area they are the barycentric weights of the opposite vertex.
    std::array<double, 3> A, B, C;
    const double inv_area = 1.0 / area;  // one division a triangle: most cover a few pixels only
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      A[i] = (sv[j] - sv[k]) * inv_area;
      B[i] = (su[k] - su[j]) * inv_area;
      C[i] = (su[j] * sv[k] - su[k] * sv[j]) * inv_area;
    }
    const double eps = -1e-9;  // pixel centres on an edge belong to both triangles: no cracks
    // In a wide triangle, the row's pixels inside all three edges form one run: each edge bounds u
    // from one side where its A is non-zero. Solved for u, widened by a pixel against rounding, and
    // then every pixel of the run tested exactly as below: the same pixels as a test of the whole
    // bounding box row, without the empty half of the box. (A narrow one's box is tested whole: the
    // run would cost more to find than it saves.)
    const bool find_runs = u1 - u0 >= 8;
    std::array<double, 3> inv_A{};
    for (int i = 0; i < 3 && find_runs; ++i) inv_A[i] = A[i] != 0 ? 1.0 / A[i] : 0.0;
    for (int v = v0; v <= v1; ++v) {
      double lo = u0, hi = u1;
      for (int i = 0; i < 3 && find_runs; ++i) {
        const double rest = B[i] * v + C[i];
        if (A[i] > 0) lo = std::max(lo, std::floor((eps - rest) * inv_A[i]) - 1);
        else if (A[i] < 0) hi = std::min(hi, std::ceil((eps - rest) * inv_A[i]) + 1);
        else if (rest < eps) hi = lo - 1;  // an edge along the row, with the row outside it
      }
      if (!(lo <= hi)) continue;  // (NaN too)
      const int run0 = static_cast<int>(lo), run1 = static_cast<int>(hi);
      for (int u = run0; u <= run1; ++u) {
        const double w0 = A[0] * u + B[0] * v + C[0];
        const double w1 = A[1] * u + B[1] * v + C[1];
        const double w2 = A[2] * u + B[2] * v + C[2];
        if (w0 < eps || w1 < eps || w2 < eps) continue;
        const double z = 1.0 / (w0 * inv_z[0] + w1 * inv_z[1] + w2 * inv_z[2]);
        const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(K_.width) + static_cast<std::size_t>(u);
        float& depth = frame_.depth.depth_m[i];
        if (!(z >= depth)) {  // also true when depth is NaN (nothing drawn yet)
          depth = static_cast<float>(z);
          if (instances_) frame_.instance[i] = instance;
          if (normals_) frame_.normal[i] = n;
        }
      }
    }
  }

 private:
  const CameraIntrinsics& K_;
  RenderedFrame& frame_;
  bool normals_, instances_;
  int closed_winding_;
};

// Cuts a triangle at z = near; returns 0, 1 or 2 triangles in front of it (as a fan of `out`).
int clip_near(const std::array<Eigen::Vector3d, 3>& tri, double near, std::array<Eigen::Vector3d, 4>& out) {
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& a = tri[i];
    const Eigen::Vector3d& b = tri[(i + 1) % 3];
    const bool a_in = a.z() >= near, b_in = b.z() >= near;
    if (a_in) out[n++] = a;
    if (a_in != b_in) out[n++] = a + (b - a) * ((near - a.z()) / (b.z() - a.z()));
  }
  return n;  // a polygon of n vertices, n in {0, 3, 4}
}

}  // namespace

RenderedFrame render(std::span<const MeshInstance> instances, const CameraIntrinsics& K, const RenderOptions& options) {
  K.validate();
  if (!(options.near_m > 0)) throw Error(fmt::format("render: near plane {} must be positive", options.near_m));
  RenderedFrame frame;
  frame.depth = DepthImage(K.width, K.height);
  if (options.instances) frame.instance.assign(frame.depth.depth_m.size(), -1);
  if (options.normals) frame.normal.assign(frame.depth.depth_m.size(), Eigen::Vector3f::Zero());
  TriangleRasterizer raster(K, frame, options.normals, options.instances, options.closed_winding);
  std::vector<ProjectedVertex> vertices;  // each vertex transformed and projected once
  for (std::size_t m = 0; m < instances.size(); ++m) {
    const TriangleMesh& mesh = *instances[m].mesh;
    mesh.check_consistent();
    vertices.resize(mesh.vertices.size());
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
      vertices[v] = project(K, instances[m].T_camera_object * mesh.vertices[v].cast<double>());
    }
    const auto id = static_cast<std::int32_t>(m);
    for (const auto& t : mesh.triangles) {
      const ProjectedVertex &a = vertices[t[0]], &b = vertices[t[1]], &c = vertices[t[2]];
      if (a.p.z() >= options.near_m && b.p.z() >= options.near_m && c.p.z() >= options.near_m) {
        raster.draw(a, b, c, id);
        continue;
      }
      std::array<Eigen::Vector3d, 4> poly;
      const int n = clip_near({a.p, b.p, c.p}, options.near_m, poly);
      for (int k = 1; k + 1 < n; ++k) {
        raster.draw(project(K, poly[0]), project(K, poly[static_cast<std::size_t>(k)]),
                    project(K, poly[static_cast<std::size_t>(k + 1)]), id);
      }
    }
  }
  return frame;
}

RenderedFrame render_points(std::span<const Eigen::Vector3f> points, const Transform& T, const CameraIntrinsics& K,
                            float spacing_m) {
  K.validate();
  RenderedFrame frame;
  frame.depth = DepthImage(K.width, K.height);
  frame.instance.assign(frame.depth.depth_m.size(), -1);
  for (const Eigen::Vector3f& p_object : points) {
    const Eigen::Vector3d p = T * p_object.cast<double>();
    if (!(p.z() > 0.01)) continue;
    const Eigen::Vector2d uv = K.project(p);
    const int half = std::max(0, static_cast<int>(std::ceil(0.5 * K.fx * spacing_m / p.z())));
    const int u0 = static_cast<int>(std::lround(uv.x())), v0 = static_cast<int>(std::lround(uv.y()));
    for (int v = std::max(0, v0 - half); v <= std::min(K.height - 1, v0 + half); ++v) {
      for (int u = std::max(0, u0 - half); u <= std::min(K.width - 1, u0 + half); ++u) {
        float& z = frame.depth.at(u, v);
        if (!(p.z() >= z)) {
          z = static_cast<float>(p.z());
          frame.instance[static_cast<std::size_t>(v) * static_cast<std::size_t>(K.width) + static_cast<std::size_t>(u)] = 0;
        }
      }
    }
  }
  return frame;
}

std::vector<RenderedFrame> render_views(const TriangleMesh& mesh, std::span<const Transform> T_camera_object,
                                        const CameraIntrinsics& K, const RenderOptions& options) {
  K.validate();
  mesh.check_consistent();
  std::vector<RenderedFrame> frames(T_camera_object.size());
  FirstException failed;
#pragma omp parallel for schedule(dynamic)
  for (std::size_t i = 0; i < T_camera_object.size(); ++i) {
    failed.run(static_cast<std::ptrdiff_t>(i), [&] {
      const MeshInstance instance{&mesh, T_camera_object[i]};
      frames[i] = render(std::span(&instance, 1), K, options);
    });
  }
  failed.rethrow();
  return frames;
}

}  // namespace viewpose
