#include "viewpose/eval/bop_scores.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <numeric>
#include <set>
#include <tuple>
#include <utility>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/eval/evaluate.hpp"
#include "viewpose/eval/metrics.hpp"
#include "viewpose/render/rasterizer.hpp"

namespace viewpose {

std::vector<double> bop_fractions() {
  std::vector<double> f;
  for (int k = 1; k <= 10; ++k) f.push_back(0.05 * k);
  return f;
}

std::vector<bool> results_taking_part(std::span<const BopResult> results,
                                      const std::optional<std::vector<BopTarget>>& targets) {
  if (!targets) return std::vector<bool>(results.size(), true);
  std::map<std::tuple<int, int, int>, int> count;  // (scene, image, object) -> inst_count
  for (const BopTarget& t : *targets) count[{t.scene_id, t.im_id, t.obj_id}] = t.inst_count;
  std::map<std::tuple<int, int, int>, std::vector<std::size_t>> listed;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const BopResult& r = results[i];
    const std::tuple<int, int, int> key{r.scene_id, r.im_id, r.obj_id};
    if (count.count(key)) listed[key].push_back(i);
  }
  std::vector<bool> part(results.size(), false);
  for (auto& [key, indices] : listed) {
    std::stable_sort(indices.begin(), indices.end(),
                     [&](std::size_t a, std::size_t b) { return results[a].score > results[b].score; });
    const std::size_t keep = std::min(indices.size(), static_cast<std::size_t>(count.at(key)));
    for (std::size_t k = 0; k < keep; ++k) part[indices[k]] = true;
  }
  return part;
}

float DistanceWindow::at(int u, int v) const {
  if (u < u0 || v < v0 || u >= u0 + width || v >= v0 + height) return std::numeric_limits<float>::quiet_NaN();
  return distance_m[static_cast<std::size_t>(v - v0) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u - u0)];
}

double depth_to_distance(double z, int u, int v, const CameraIntrinsics& K) {
  if (!(z > 0)) return std::numeric_limits<double>::quiet_NaN();
  const double x = (u - K.cx) / K.fx, y = (v - K.cy) / K.fy;
  return z * std::sqrt(x * x + y * y + 1.0);
}

DistanceWindow projected_window(const TriangleMesh& mesh, const Transform& T_camera_object, const CameraIntrinsics& K) {
  // Only the window the model's bounding box projects to can hold it (the box's projection holds
  // the model's whenever the whole box is in front of the camera); drawing just that is what keeps
  // VSD fast, as most objects cover a small part of the image.
  const RenderOptions defaults;
  int u0 = 0, v0 = 0, u1 = K.width - 1, v1 = K.height - 1;  // inclusive
  const BoundingBox box = bounding_box(mesh);
  if (box.empty) return {};
  double lo_u = std::numeric_limits<double>::infinity(), lo_v = lo_u, hi_u = -lo_u, hi_v = -lo_u;
  bool in_front = true;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p(corner & 1 ? box.max.x() : box.min.x(), corner & 2 ? box.max.y() : box.min.y(),
                            corner & 4 ? box.max.z() : box.min.z());
    const Eigen::Vector3d c = T_camera_object * p;
    if (!(c.z() > defaults.near_m)) {
      in_front = false;  // clipped at the near plane: the box's corners bound nothing; draw it all
      break;
    }
    const Eigen::Vector2d uv = K.project(c);
    lo_u = std::min(lo_u, uv.x()), hi_u = std::max(hi_u, uv.x());
    lo_v = std::min(lo_v, uv.y()), hi_v = std::max(hi_v, uv.y());
  }
  if (in_front) {
    // Pixel centres at integer coordinates: those inside [lo, hi].
    u0 = static_cast<int>(std::clamp(std::ceil(lo_u), 0.0, static_cast<double>(K.width)));
    v0 = static_cast<int>(std::clamp(std::ceil(lo_v), 0.0, static_cast<double>(K.height)));
    u1 = static_cast<int>(std::clamp(std::floor(hi_u), -1.0, static_cast<double>(K.width - 1)));
    v1 = static_cast<int>(std::clamp(std::floor(hi_v), -1.0, static_cast<double>(K.height - 1)));
  }
  DistanceWindow w;
  if (u1 < u0 || v1 < v0) return w;  // entirely outside the image
  w.u0 = u0;
  w.v0 = v0;
  w.width = u1 - u0 + 1;
  w.height = v1 - v0 + 1;
  return w;
}

bool DistanceWindow::overlaps(const DistanceWindow& o) const {
  return width > 0 && height > 0 && o.width > 0 && o.height > 0 && u0 < o.u0 + o.width && o.u0 < u0 + width &&
         v0 < o.v0 + o.height && o.v0 < v0 + height;
}

DistanceWindow render_distance(const TriangleMesh& mesh, const Transform& T_camera_object, const CameraIntrinsics& K,
                               int closed_winding) {
  DistanceWindow w = projected_window(mesh, T_camera_object, K);
  if (w.width == 0 || w.height == 0) return w;
  const int u0 = w.u0, v0 = w.v0;
  // Window pixel (x, y) is image pixel (u0 + x, v0 + y): the same principal point, moved.
  CameraIntrinsics Kw = K;
  Kw.cx = K.cx - u0;
  Kw.cy = K.cy - v0;
  Kw.width = w.width;
  Kw.height = w.height;
  const MeshInstance instance{&mesh, T_camera_object};
  RenderOptions options;
  options.instances = false;
  options.closed_winding = closed_winding;
  const RenderedFrame frame = render(std::span(&instance, 1), Kw, options);
  w.distance_m.resize(frame.depth.depth_m.size());
  for (int y = 0; y < w.height; ++y)
    for (int x = 0; x < w.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w.width) + static_cast<std::size_t>(x);
      w.distance_m[i] = static_cast<float>(depth_to_distance(frame.depth.depth_m[i], u0 + x, v0 + y, K));
    }
  return w;
}

std::vector<double> vsd_errors(const DepthImage& test, const CameraIntrinsics& K, const DistanceWindow& est,
                               const DistanceWindow& gt, double delta, std::span<const double> taus, double diameter) {
  // Over the union of the two windows: elsewhere neither drawing has a surface.
  const bool has_est = est.width > 0 && est.height > 0, has_gt = gt.width > 0 && gt.height > 0;
  std::vector<double> errors(taus.size(), 1.0);  // an empty union: e = 1, as the toolkit
  if (!has_est && !has_gt) return errors;
  const int u0 = std::max(0, std::min(has_est ? est.u0 : gt.u0, has_gt ? gt.u0 : est.u0));
  const int v0 = std::max(0, std::min(has_est ? est.v0 : gt.v0, has_gt ? gt.v0 : est.v0));
  const int u1 = std::min(test.width, std::max(has_est ? est.u0 + est.width : 0, has_gt ? gt.u0 + gt.width : 0));
  const int v1 = std::min(test.height, std::max(has_est ? est.v0 + est.height : 0, has_gt ? gt.v0 + gt.height : 0));
  std::size_t union_count = 0, inter_count = 0;
  std::vector<std::size_t> far(taus.size(), 0);  // intersection pixels at or beyond each tau
  for (int v = v0; v < v1; ++v)
    for (int u = u0; u < u1; ++u) {
      const double d_est = est.at(u, v), d_gt = gt.at(u, v);
      const bool drawn_est = d_est > 0, drawn_gt = d_gt > 0;  // false for NaN
      if (!drawn_est && !drawn_gt) continue;
      const double d_test = depth_to_distance(test.at(u, v), u, v, K);
      const bool missing = std::isnan(d_test);
      // BOP19 visibility: visible where not behind the test surface by more than delta, or where
      // the test depth is missing (shiny objects); the estimate is also visible wherever the truth is.
      const bool visib_gt = drawn_gt && (missing || d_gt - d_test <= delta);
      const bool visib_est = drawn_est && (missing || d_est - d_test <= delta || visib_gt);
      if (!visib_gt && !visib_est) continue;
      ++union_count;
      if (!(visib_gt && visib_est)) continue;
      ++inter_count;
      const double dist = std::abs(d_gt - d_est) / diameter;
      for (std::size_t t = 0; t < taus.size(); ++t) far[t] += dist >= taus[t];
    }
  if (union_count == 0) return errors;
  for (std::size_t t = 0; t < taus.size(); ++t)
    errors[t] = static_cast<double>(far[t] + union_count - inter_count) / static_cast<double>(union_count);
  return errors;
}

namespace {

struct ObjectData {
  const TriangleMesh* mesh = nullptr;
  std::vector<Transform> symmetries;
  double diameter_m = 0;
  int closed_winding = 0;
};

// Matched counts of one image, per object.
struct ImageCounts {
  std::map<int, BopRecall> per_object;
  int estimates_used = 0;
  double mspd_scale = 0;  // 0: no frame was read
  std::exception_ptr error;
};

// An estimate's errors against each ground truth of its object in the image.
struct EstimateErrors {
  std::size_t result = 0;
  std::vector<std::size_t> gts;         // indices into the image's gt
  std::vector<std::vector<double>> vsd;  // per gt, per tau
  std::vector<double> mssd_m, mspd_px;  // per gt
};

// Greedy matching by decreasing score (the estimates come sorted): each estimate to the unmatched
// valid ground truth of lowest error below `threshold`. Returns the count of valid ones matched.
template <class ErrorOf>
int match(const std::vector<EstimateErrors>& estimates, const std::vector<bool>& valid, double threshold,
          const ErrorOf& error_of) {
  std::vector<bool> matched(valid.size(), false);
  int found = 0;
  for (const EstimateErrors& e : estimates) {
    std::optional<std::size_t> best;
    double best_error = threshold;
    for (std::size_t k = 0; k < e.gts.size(); ++k) {
      const std::size_t g = e.gts[k];
      if (!valid[g] || matched[g]) continue;
      const double err = error_of(e, k);
      if (err < best_error) {
        best = g;
        best_error = err;
      }
    }
    if (best) {
      matched[*best] = true;
      ++found;
    }
  }
  return found;
}

void size_counts(BopRecall& r, const BopScoreOptions& o) {
  r.found_vsd.resize(o.vsd_taus.size() * o.vsd_thresholds.size(), 0);
  r.found_mssd.resize(o.mssd_fractions.size(), 0);
  r.found_mspd.resize(o.mspd_px.size(), 0);
}

ImageCounts score_image(const BopImage& im, std::span<const BopResult> results, const std::vector<std::size_t>& used,
                        const std::map<int, ObjectData>& objects, const std::set<int>* listed_objects,
                        const BopScoreOptions& o) {
  ImageCounts out;
  out.estimates_used = static_cast<int>(used.size());
  std::vector<bool> valid(im.gt.size());
  const bool have_info = im.gt_info.size() == im.gt.size();
  for (std::size_t g = 0; g < im.gt.size(); ++g) {
    const int id = im.gt[g].obj_id;
    valid[g] = (!have_info || im.gt_info[g].visib_fract >= o.min_visib_fract) && (!listed_objects || listed_objects->count(id));
    if (valid[g]) {
      BopRecall& r = out.per_object[id];
      size_counts(r, o);
      ++r.targets;
    }
  }
  // Estimates by object, by decreasing score; only objects with ground truth here can match.
  std::map<int, std::vector<EstimateErrors>> by_object;
  std::set<int> gt_objects;
  for (const GroundTruthPose& g : im.gt) gt_objects.insert(g.obj_id);
  for (std::size_t i : used)
    if (gt_objects.count(results[i].obj_id)) by_object[results[i].obj_id].push_back({i, {}, {}, {}, {}});
  if (by_object.empty()) return out;
  for (auto& [id, list] : by_object)
    std::stable_sort(list.begin(), list.end(),
                     [&](const EstimateErrors& a, const EstimateErrors& b) { return results[a.result].score > results[b.result].score; });

  const BopFrame frame = o.load_frame ? o.load_frame(im) : load_bop_frame(im);
  out.mspd_scale = frame.K.width / 640.0;
  std::map<std::size_t, DistanceWindow> gt_drawn;  // drawn once, for every estimate of its object
  for (auto& [id, list] : by_object) {
    const ObjectData& object = objects.at(id);
    for (std::size_t g = 0; g < im.gt.size(); ++g)
      if (im.gt[g].obj_id == id)
        gt_drawn[g] = render_distance(*object.mesh, im.gt[g].T_camera_object, frame.K, object.closed_winding);
    for (EstimateErrors& e : list) {
      const Transform& T = results[e.result].T_camera_object;
      // An estimate whose window meets no truth's shares no pixel with any: e = 1 against each
      // (the toolkit's shortcut too), and it need not be drawn. Far-off false positives are common.
      const DistanceWindow window = projected_window(*object.mesh, T, frame.K);
      bool meets = false;
      for (const auto& [g, drawn_gt] : gt_drawn) meets = meets || (im.gt[g].obj_id == id && window.overlaps(drawn_gt));
      const DistanceWindow drawn = meets ? render_distance(*object.mesh, T, frame.K, object.closed_winding) : window;
      for (std::size_t g = 0; g < im.gt.size(); ++g) {
        if (im.gt[g].obj_id != id) continue;
        const Transform& truth = im.gt[g].T_camera_object;
        e.gts.push_back(g);
        e.vsd.push_back(drawn.overlaps(gt_drawn.at(g))
                            ? vsd_errors(frame.depth, frame.K, drawn, gt_drawn.at(g), o.vsd_delta_m, o.vsd_taus, object.diameter_m)
                            : std::vector<double>(o.vsd_taus.size(), 1.0));
        e.mssd_m.push_back(mssd_error(T, truth, object.mesh->vertices, object.symmetries));
        e.mspd_px.push_back(mspd_error(T, truth, object.mesh->vertices, object.symmetries, frame.K));
      }
    }
  }

  // Matching, for every error, threshold and tau on its own.
  for (const auto& [id, list] : by_object) {
    const auto row = out.per_object.find(id);
    if (row == out.per_object.end()) continue;  // no valid ground truth: nothing to find
    BopRecall& r = row->second;
    const double diameter = objects.at(id).diameter_m;
    for (std::size_t t = 0; t < o.vsd_taus.size(); ++t)
      for (std::size_t k = 0; k < o.vsd_thresholds.size(); ++k)
        r.found_vsd[t * o.vsd_thresholds.size() + k] +=
            match(list, valid, o.vsd_thresholds[k], [t](const EstimateErrors& e, std::size_t j) { return e.vsd[j][t]; });
    for (std::size_t k = 0; k < o.mssd_fractions.size(); ++k)
      r.found_mssd[k] += match(list, valid, o.mssd_fractions[k] * diameter,
                               [](const EstimateErrors& e, std::size_t j) { return e.mssd_m[j]; });
    for (std::size_t k = 0; k < o.mspd_px.size(); ++k)
      r.found_mspd[k] += match(list, valid, o.mspd_px[k] * out.mspd_scale,
                               [](const EstimateErrors& e, std::size_t j) { return e.mspd_px[j]; });
  }
  return out;
}

void add_counts(BopRecall& into, const BopRecall& from, const BopScoreOptions& o) {
  size_counts(into, o);
  into.targets += from.targets;
  for (std::size_t k = 0; k < from.found_vsd.size(); ++k) into.found_vsd[k] += from.found_vsd[k];
  for (std::size_t k = 0; k < from.found_mssd.size(); ++k) into.found_mssd[k] += from.found_mssd[k];
  for (std::size_t k = 0; k < from.found_mspd.size(); ++k) into.found_mspd[k] += from.found_mspd[k];
}

double mean_recall(const std::vector<int>& found, int targets) {
  if (targets == 0 || found.empty()) return 0.0;
  const double sum = std::accumulate(found.begin(), found.end(), 0.0);
  return sum / static_cast<double>(targets) / static_cast<double>(found.size());
}

void finish(BopRecall& r) {
  r.ar_vsd = mean_recall(r.found_vsd, r.targets);
  r.ar_mssd = mean_recall(r.found_mssd, r.targets);
  r.ar_mspd = mean_recall(r.found_mspd, r.targets);
}

}  // namespace

BopScores score_bop(const BopDataset& ds, const std::map<int, TriangleMesh>& meshes, std::span<const BopResult> results,
                    const BopScoreOptions& o) {
  const std::vector<bool> part = results_taking_part(results, o.targets);
  std::map<std::pair<int, int>, std::set<int>> listed;  // per image, the objects its targets name
  if (o.targets)
    for (const BopTarget& t : *o.targets) listed[{t.scene_id, t.im_id}].insert(t.obj_id);
  std::map<std::pair<int, int>, std::vector<std::size_t>> by_image;
  for (std::size_t i = 0; i < results.size(); ++i)
    if (part[i]) by_image[{results[i].scene_id, results[i].im_id}].push_back(i);

  // The objects that matter: ground truths anywhere, estimates taking part in the split's images.
  std::set<int> ids;
  for (const BopImage& im : ds.images) {
    for (const GroundTruthPose& g : im.gt) ids.insert(g.obj_id);
    const auto found = by_image.find({im.scene_id, im.im_id});
    if (found != by_image.end())
      for (std::size_t i : found->second) ids.insert(results[i].obj_id);
  }
  std::map<int, ObjectData> objects;
  for (int id : ids) {
    const auto mesh = meshes.find(id);
    if (mesh == meshes.end() || mesh->second.vertices.empty()) throw Error(fmt::format("eval: no model for object {}", id));
    ObjectData& data = objects[id];
    data.mesh = &mesh->second;
    data.closed_winding = closed_mesh_winding(mesh->second);
    ObjectScale scale = object_scale(ds.models, id, o.symmetry_step);
    data.diameter_m = scale.diameter_m;
    data.symmetries = std::move(scale.symmetries);
    if (!(data.diameter_m > 0)) data.diameter_m = mesh_diameter(mesh->second);
    if (!(data.diameter_m > 0)) throw Error(fmt::format("eval: object {} has no size", id));
  }

  const std::vector<std::size_t> none;
  const std::set<int> no_objects;
  std::vector<ImageCounts> counts(ds.images.size());
  // Each image on its own, summed in the images' order afterwards: the same for any thread count.
#pragma omp parallel for schedule(dynamic)
  for (std::size_t i = 0; i < ds.images.size(); ++i) {
    const BopImage& im = ds.images[i];
    const auto found = by_image.find({im.scene_id, im.im_id});
    const std::set<int>* objects_listed = nullptr;
    if (o.targets) {
      const auto l = listed.find({im.scene_id, im.im_id});
      objects_listed = l == listed.end() ? &no_objects : &l->second;
    }
    try {
      counts[i] = score_image(im, results, found == by_image.end() ? none : found->second, objects, objects_listed, o);
    } catch (...) {
      counts[i].error = std::current_exception();
    }
  }

  BopScores s;
  s.targets_mode = o.targets.has_value();
  s.images = static_cast<int>(ds.images.size());
  size_counts(s.total, o);
  bool scale_known = false;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    if (counts[i].error) std::rethrow_exception(counts[i].error);  // the first image's, whatever the threads
    s.estimates_used += counts[i].estimates_used;
    if (!scale_known && counts[i].mspd_scale > 0) {
      s.mspd_scale = counts[i].mspd_scale;
      scale_known = true;
    }
    for (const auto& [id, r] : counts[i].per_object) {
      add_counts(s.per_object[id], r, o);
      add_counts(s.per_scene[ds.images[i].scene_id], r, o);
      add_counts(s.total, r, o);
    }
  }
  finish(s.total);
  for (auto& [id, r] : s.per_object) finish(r);
  for (auto& [id, r] : s.per_scene) finish(r);
  return s;
}

}  // namespace viewpose
