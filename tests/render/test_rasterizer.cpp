#include <cmath>
#include <array>
#include <numbers>
#include <random>
#include <utility>
#include <vector>
#include <string>

#include "test_support.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/render/view_sphere.hpp"

namespace viewpose {
namespace {

const CameraIntrinsics K = CameraIntrinsics::kinect_v1();

Transform at(const Eigen::Vector3d& t, const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) { return make_transform(R, t); }

RenderedFrame render_one(const TriangleMesh& mesh, const Transform& T, bool normals = false) {
  const MeshInstance inst{&mesh, T};
  RenderOptions o;
  o.normals = normals;
  return render(std::span(&inst, 1), K, o);
}

// The same depth at every pixel (NaN where neither drew anything).
void expect_same_depth(const DepthImage& a, const DepthImage& b) {
  ASSERT_EQ(a.depth_m.size(), b.depth_m.size());
  for (std::size_t i = 0; i < a.depth_m.size(); ++i) {
    const float x = a.depth_m[i], y = b.depth_m[i];
    ASSERT_TRUE(x == y || (std::isnan(x) && std::isnan(y))) << "pixel " << i << ": " << x << " against " << y;
  }
}

// A closed mesh drawn whole and drawn with the back faces of winding +1 skipped: the same picture.
void expect_fronts_alone_draw_the_same(const TriangleMesh& mesh, const Transform& T) {
  const RenderedFrame all = render_one(mesh, T);
  const MeshInstance inst{&mesh, T};
  RenderOptions culled;
  culled.closed_winding = 1;
  const RenderedFrame fronts = render(std::span(&inst, 1), K, culled);
  ASSERT_GT(all.depth.count_valid(), 1000u);
  expect_same_depth(all.depth, fronts.depth);
}

TEST(Rasterizer, PlaneAtKnownDistanceFillsEveryPixelAtThatDepth) {
  const TriangleMesh wall = test::square(10.0f);
  const RenderedFrame f = render_one(wall, at({0, 0, 1.2}), true);
  ASSERT_EQ(f.depth.count_valid(), 640u * 480u);
  for (float z : f.depth.depth_m) ASSERT_NEAR(z, 1.2f, 1e-6f);
  for (auto id : f.instance) ASSERT_EQ(id, 0);
  EXPECT_TRUE(f.normal[1000].isApprox(Eigen::Vector3f(0, 0, -1), 1e-6f));  // facing the camera
}

TEST(Rasterizer, TiltedPlaneIsPerspectiveCorrect) {
  // Plane z = 1 + 0.5 x: on the ray x = a z it meets z = 1 / (1 - 0.5 a), exactly.
  const double tilt = std::atan(0.5);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(-tilt, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const TriangleMesh wall = test::square(3.0f);
  const RenderedFrame f = render_one(wall, at({0, 0, 1}, R));
  for (int u : {0, 100, 319, 500, 639}) {
    const double a = (u - K.cx) / K.fx;
    EXPECT_NEAR(f.depth.at(u, 240), 1.0 / (1.0 - 0.5 * a), 2e-6) << u;
  }
}

TEST(Rasterizer, BoxFaceDepthAndSilhouette) {
  // A 0.2 m cube 1 m away: its front face at 0.9 m spans fx * 0.1 / 0.9 = 58.3 px either side.
  const TriangleMesh cube = make_box_mesh({0.2f, 0.2f, 0.2f});
  const RenderedFrame f = render_one(cube, at({0, 0, 1}));
  EXPECT_NEAR(f.depth.at(319, 239), 0.9f, 1e-6f);
  EXPECT_TRUE(std::isfinite(f.depth.at(319 + 58, 239)));
  EXPECT_FALSE(std::isfinite(f.depth.at(320 + 59, 239)));
  // Pixel centres from 261.17 to 377.83: columns 262 to 377.
  int row = 0;
  for (int u = 0; u < 640; ++u) row += std::isfinite(f.depth.at(u, 239)) ? 1 : 0;
  EXPECT_EQ(row, 116);
}

TEST(Rasterizer, SphereSilhouetteHasTheAnalyticRadius) {
  // A fine UV sphere; its outline seen from distance D has radius f R / sqrt(D^2 - R^2) pixels.
  const double R = 0.1, D = 0.8;
  const TriangleMesh sphere = make_sphere(R);
  const RenderedFrame f = render_one(sphere, at({0, 0, D}));
  const double r_px = K.fx * R / std::sqrt(D * D - R * R);
  const double area = static_cast<double>(f.depth.count_valid());
  EXPECT_NEAR(std::sqrt(area / std::numbers::pi), r_px, 0.01 * r_px);
  EXPECT_NEAR(f.depth.at(319, 239), D - R, 1e-4);  // the nearest point, on the axis
}

TEST(Rasterizer, NearerSurfaceWinsAndInstancesAreLabelled) {
  const TriangleMesh wall = test::square(5.0f), card = test::square(0.1f);
  const MeshInstance scene[] = {{&wall, at({0, 0, 2})}, {&card, at({0, 0, 1})}};
  const RenderedFrame f = render(scene, K);
  EXPECT_EQ(f.instance[240 * 640 + 320], 1);
  EXPECT_NEAR(f.depth.at(320, 240), 1.0f, 1e-6f);
  EXPECT_EQ(f.instance[10], 0);
  EXPECT_NEAR(f.depth.at(10, 0), 2.0f, 1e-6f);
}

TEST(Rasterizer, TrianglesCrossingTheNearPlaneAreClippedNotDropped) {
  // A floor plane y = 0.3 running from behind the camera to 5 m ahead.
  TriangleMesh floor;
  floor.vertices = {{-3, 0.3f, -1}, {3, 0.3f, -1}, {3, 0.3f, 5}, {-3, 0.3f, 5}};
  floor.triangles = {{0, 1, 2}, {0, 2, 3}};
  const RenderedFrame f = render_one(floor, Transform::Identity());
  // Row v sees the floor at z = 0.3 fy / (v - cy).
  for (int v : {300, 400, 479}) EXPECT_NEAR(f.depth.at(320, v), 0.3 * K.fy / (v - K.cy), 1e-5) << v;
  EXPECT_FALSE(std::isfinite(f.depth.at(320, 100)));  // above the horizon
}

TEST(ViewSphere, ThesisAndDenseCountsAreUniformUnitDirections) {
  for (const auto& [subdivisions, count] : {std::pair{0, 20}, std::pair{1, 80}, std::pair{2, 320}}) {
    const auto dirs = view_directions(subdivisions);
    ASSERT_EQ(dirs.size(), static_cast<std::size_t>(count));
    double min_angle = 10, max_nearest = 0;
    for (std::size_t i = 0; i < dirs.size(); ++i) {
      EXPECT_NEAR(dirs[i].norm(), 1.0, 1e-12);
      double nearest = 10;
      for (std::size_t j = 0; j < dirs.size(); ++j) {
        if (i != j) nearest = std::min(nearest, std::acos(std::clamp(dirs[i].dot(dirs[j]), -1.0, 1.0)));
      }
      min_angle = std::min(min_angle, nearest);
      max_nearest = std::max(max_nearest, nearest);
    }
    EXPECT_LT(max_nearest / min_angle, 1.5) << "views should be spread evenly";
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& d : dirs) sum += d;
    EXPECT_LT(sum.norm(), 1e-9);  // symmetric: no side of the object is favoured
  }
}

TEST(ViewSphere, LookAtPutsTheTargetAtThePrincipalPointUpright) {
  const Eigen::Vector3d eye(0.5, -0.8, 0.3), target(0.01, 0.02, -0.03);
  const Transform T = look_at(eye, target);
  EXPECT_TRUE((T * eye).isZero(1e-12));
  const Eigen::Vector3d t = T * target;
  EXPECT_NEAR(t.x(), 0, 1e-12);
  EXPECT_NEAR(t.y(), 0, 1e-12);
  EXPECT_NEAR(t.z(), (eye - target).norm(), 1e-12);
  // A point above the target (object +z) appears higher in the image (smaller v).
  EXPECT_LT((T * (target + Eigen::Vector3d(0, 0, 0.1))).y(), 0);
  // Straight down the up axis still gives a valid rotation.
  EXPECT_TRUE(is_rotation(look_at({0, 0, 1}, {0, 0, 0}).linear()));
}

TEST(ViewSphere, EveryRenderedViewMapsBackOntoTheModelWithinAMillimetre) {
  // PCL's tessellated-sphere renderer produces views that cannot be mapped back (PCL issues 3314
  // and 2188); ours must: every pixel, carried into the object frame by the recorded pose, lies on
  // the model's surface.
  const TriangleMesh jug = make_jug();
  const auto poses = view_sphere_poses(Eigen::Vector3d::Zero(), 0.7, 1);
  const auto frames = render_views(jug, poses, K);
  ASSERT_EQ(frames.size(), 80u);
  double worst = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const PointCloud cloud = depth_to_cloud(frames[i].depth, K);
    ASSERT_GT(cloud.count_finite(), 2000u) << "view " << i;
    std::size_t k = 0;
    for (const auto& p : cloud.points) {
      if (!p.allFinite() || (k++ % 97) != 0) continue;
      worst = std::max(worst, distance_to_surface(jug, poses[i].inverse() * p.cast<double>()));
    }
  }
  EXPECT_LT(worst, 0.001);
}

TEST(Shapes, JugHasTheThesisBottlesProportionsAndAHandle) {
  const TriangleMesh jug = make_jug();
  jug.check_consistent();
  const BoundingBox b = bounding_box(jug);
  EXPECT_NEAR(b.size().x(), 0.17, 0.005);
  EXPECT_NEAR(b.size().y(), 0.11, 0.005);
  EXPECT_NEAR(b.size().z(), 0.27 + 0.035 + 0.002, 0.01);  // body, cap (sunk 5 mm), and the handle's arch
  EXPECT_TRUE((0.5f * (b.min + b.max)).isZero(1e-6f));
  // Not symmetric under a half turn about z: the handle and cap tell the sides apart.
  const Eigen::Matrix3d half_turn = Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  double far = 0;
  for (std::size_t i = 0; i < jug.vertices.size(); i += 13) {
    far = std::max(far, distance_to_surface(jug, half_turn * jug.vertices[i].cast<double>()));
  }
  EXPECT_GT(far, 0.01);  // parts land more than 1 cm from any surface after the turn
  for (const auto& name : shape_names()) EXPECT_GT(make_named_shape(name).triangles.size(), 10u) << name;
  test::expect_error([] { make_named_shape("teapot"); }, "unknown shape 'teapot'");
}

}  // namespace
}  // namespace viewpose

namespace viewpose {
namespace {

TEST(Rasterizer, ClosedMeshesDrawnWithoutBackFacesGiveTheSamePicture) {
  const Transform T = make_transform(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix(), {0.05, 0.02, 0.8});
  for (const std::string& name : shape_names()) {
    SCOPED_TRACE(name);
    const TriangleMesh mesh = make_named_shape(name);
    ASSERT_EQ(closed_mesh_winding(mesh), 1) << "the built-in shapes are closed and wound outwards";
    expect_fronts_alone_draw_the_same(mesh, T);
    const RenderedFrame all = render_one(mesh, T);
    const MeshInstance inst{&mesh, T};
    // Wound the other way round, the same faces are the back ones: nothing of the front is drawn.
    RenderOptions culled;
    culled.closed_winding = -1;
    const RenderedFrame backs = render(std::span(&inst, 1), K, culled);
    std::size_t nearer = 0;
    for (std::size_t i = 0; i < all.depth.depth_m.size(); ++i) nearer += backs.depth.depth_m[i] <= all.depth.depth_m[i] ? 1 : 0;
    EXPECT_EQ(nearer, 0u);
  }
}

// The textbook rasterizer: every pixel centre of a triangle's bounding box tested against its three
// edge functions, with the same arithmetic as render(); no near clipping (all triangles in front).
DepthImage draw_by_bounding_box(const TriangleMesh& mesh, const Transform& T) {
  DepthImage d(K.width, K.height);
  struct P {
    Eigen::Vector3d p;
    double su, sv, inv_z;
  };
  std::vector<P> vs;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    const Eigen::Vector3d p = T * v.cast<double>();
    const double iz = 1.0 / p.z();
    vs.push_back({p, K.fx * p.x() * iz + K.cx, K.fy * p.y() * iz + K.cy, iz});
  }
  for (const auto& t : mesh.triangles) {
    const std::array<double, 3> su = {vs[t[0]].su, vs[t[1]].su, vs[t[2]].su}, sv = {vs[t[0]].sv, vs[t[1]].sv, vs[t[2]].sv};
    const std::array<double, 3> iz = {vs[t[0]].inv_z, vs[t[1]].inv_z, vs[t[2]].inv_z};
    const double area = (su[1] - su[0]) * (sv[2] - sv[0]) - (sv[1] - sv[0]) * (su[2] - su[0]);
    if (!(std::abs(area) > 1e-12)) continue;
    const double inv_area = 1.0 / area;
    std::array<double, 3> A, B, C;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      A[i] = (sv[j] - sv[k]) * inv_area;
      B[i] = (su[k] - su[j]) * inv_area;
      C[i] = (su[j] * sv[k] - su[k] * sv[j]) * inv_area;
    }
    const int u0 = std::max(0, static_cast<int>(std::ceil(std::min({su[0], su[1], su[2]}))));
    const int u1 = std::min(K.width - 1, static_cast<int>(std::floor(std::max({su[0], su[1], su[2]}))));
    const int v0 = std::max(0, static_cast<int>(std::ceil(std::min({sv[0], sv[1], sv[2]}))));
    const int v1 = std::min(K.height - 1, static_cast<int>(std::floor(std::max({sv[0], sv[1], sv[2]}))));
    for (int v = v0; v <= v1; ++v)
      for (int u = u0; u <= u1; ++u) {
        const double w0 = A[0] * u + B[0] * v + C[0], w1 = A[1] * u + B[1] * v + C[1], w2 = A[2] * u + B[2] * v + C[2];
        if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
        const double z = 1.0 / (w0 * iz[0] + w1 * iz[1] + w2 * iz[2]);
        float& depth = d.at(u, v);
        if (!(z >= depth)) depth = static_cast<float>(z);
      }
  }
  return d;
}

TEST(Rasterizer, DrawsTheSamePixelsAsTestingEveryPixelOfEachTrianglesBox) {
  // Triangles of every size and shape, slivers, some reaching beyond the image, and a grid of
  // squares whose edges and diagonals run through pixel centres (the cases rounding could decide).
  std::mt19937 rng(20261203);
  std::uniform_real_distribution<float> xy(-0.6f, 0.6f), z(0.4f, 3.0f), size(0.0005f, 0.3f), unit(-1, 1);
  TriangleMesh mesh;
  for (int t = 0; t < 3000; ++t) {
    const Eigen::Vector3f c(xy(rng), xy(rng), z(rng));
    const float s = t % 10 == 0 ? 0.5f * size(rng) * size(rng) : size(rng);
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    for (int k = 0; k < 3; ++k) mesh.vertices.push_back(c + s * Eigen::Vector3f(unit(rng), unit(rng), 0.3f * unit(rng)));
    if (t % 7 == 0) mesh.vertices.back() = mesh.vertices[base] + 1e-3f * (mesh.vertices[base + 1] - mesh.vertices[base]);  // a sliver
    mesh.triangles.push_back({base, base + 1, base + 2});
  }
  const Transform identity = Transform::Identity();
  {
    // Pixel-aligned squares at depth 1 m: their corners project onto pixel centres.
    const double z0 = 1.0;
    for (int i = 0; i < 40; ++i) {
      const double u = 100 + 11 * i, v = 60 + 9 * i, w = 3 + i % 5;
      const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
      for (const auto& [du, dv] : {std::pair{0.0, 0.0}, {w, 0.0}, {w, w}, {0.0, w}}) {
        mesh.vertices.push_back(Eigen::Vector3f(static_cast<float>((u + du - K.cx) / K.fx * z0), static_cast<float>((v + dv - K.cy) / K.fy * z0),
                                                static_cast<float>(z0)));
      }
      mesh.triangles.push_back({base, base + 1, base + 2});
      mesh.triangles.push_back({base, base + 2, base + 3});
    }
  }
  const DepthImage expected = draw_by_bounding_box(mesh, identity);
  RenderOptions o;
  o.instances = false;
  const MeshInstance inst{&mesh, identity};
  const RenderedFrame f = render(std::span(&inst, 1), K, o);
  ASSERT_GT(expected.count_valid(), 50000u);
  expect_same_depth(expected, f.depth);
}

TEST(Rasterizer, OpenOrInconsistentMeshesAreNotClosed) {
  TriangleMesh open = test::square(1.0f);
  EXPECT_EQ(closed_mesh_winding(open), 0);
  TriangleMesh box = make_box_mesh({0.1f, 0.1f, 0.1f});
  ASSERT_EQ(closed_mesh_winding(box), 1);
  std::swap(box.triangles[0][1], box.triangles[0][2]);  // one face turned inside out
  EXPECT_EQ(closed_mesh_winding(box), 0);
  TriangleMesh inside_out = make_box_mesh({0.1f, 0.1f, 0.1f});
  for (auto& t : inside_out.triangles) std::swap(t[1], t[2]);
  EXPECT_EQ(closed_mesh_winding(inside_out), -1);
  EXPECT_EQ(closed_mesh_winding(TriangleMesh{}), 0);
  // One face twice: its edges run more often one way than the other.
  TriangleMesh repeated = make_box_mesh({0.1f, 0.1f, 0.1f});
  repeated.triangles.push_back(repeated.triangles[0]);
  EXPECT_EQ(closed_mesh_winding(repeated), 0);
  // Two boxes sharing one edge (four faces along it, two each way) bound a solid all the same: seen
  // from anywhere outside, the front faces hide the back ones, so the back may be skipped.
  TriangleMesh pinched = make_box_mesh({0.1f, 0.1f, 0.1f});
  const TriangleMesh other = make_box_mesh({0.1f, 0.1f, 0.1f});
  const auto shared = [&](const Eigen::Vector3f& v) {
    // The second box moved by (0.1, 0.1, 0) meets the first along its edge x = y = 0.05.
    for (std::uint32_t i = 0; i < pinched.vertices.size(); ++i)
      if ((pinched.vertices[i] - v).norm() < 1e-6f) return i;
    pinched.vertices.push_back(v);
    return static_cast<std::uint32_t>(pinched.vertices.size() - 1);
  };
  const std::size_t first = pinched.triangles.size();
  for (const auto& t : other.triangles) {
    std::array<std::uint32_t, 3> moved{};
    for (int k = 0; k < 3; ++k) moved[static_cast<std::size_t>(k)] = shared(other.vertices[t[static_cast<std::size_t>(k)]] + Eigen::Vector3f(0.1f, 0.1f, 0));
    pinched.triangles.push_back(moved);
  }
  ASSERT_EQ(pinched.triangles.size(), first + other.triangles.size());
  ASSERT_LT(pinched.vertices.size(), 16u) << "the boxes share the two ends of an edge";
  EXPECT_EQ(closed_mesh_winding(pinched), 1);
  const Transform T = make_transform(Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, -1, 0.5).normalized()).toRotationMatrix(), {0.0, 0.0, 0.7});
  expect_fronts_alone_draw_the_same(pinched, T);
}

}  // namespace
}  // namespace viewpose
