#include "viewpose/eval/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <set>
#include <utility>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/eval/bop_scores.hpp"
#include "viewpose/eval/metrics.hpp"

namespace viewpose {

std::vector<Transform> symmetry_transforms(const ModelInfo& info, double step) {
  // As the BOP toolkit: ceil(pi / step) turns about each continuous axis.
  return symmetry_transforms(Symmetries{info.symmetries_discrete, info.symmetries_continuous},
                             static_cast<int>(std::ceil(M_PI / step)));
}

ObjectScale object_scale(const ModelsInfo& models, int obj_id, double symmetry_step) {
  const auto info = models.find(obj_id);
  if (info == models.end()) return {0.0, {Transform::Identity()}};
  return {info->second.diameter_m, symmetry_transforms(info->second, symmetry_step)};
}

namespace {

struct ObjectData {
  std::vector<Eigen::Vector3f> points;
  std::vector<Transform> symmetries;
  double diameter_m = 0;
};

std::vector<Eigen::Vector3f> thin(const std::vector<Eigen::Vector3f>& points, std::size_t at_most) {
  if (points.size() <= at_most || at_most == 0) return points;
  std::vector<Eigen::Vector3f> out;
  out.reserve(at_most);
  for (std::size_t k = 0; k < at_most; ++k) out.push_back(points[k * points.size() / at_most]);
  return out;
}

double diameter_of(std::span<const Eigen::Vector3f> points) {
  double d2 = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t j = i + 1; j < points.size(); ++j) d2 = std::max(d2, static_cast<double>((points[i] - points[j]).squaredNorm()));
  return std::sqrt(d2);
}

struct Errors {
  double add_s = 0, add = 0, mssd = 0, rotation_deg = 0, translation_mm = 0;
};

// Accumulates one row of the report.
struct Tally {
  Score score;
  std::vector<int> mssd_found;  // per threshold
  std::vector<double> rotations, translations;

  void add_target(const Errors* e, double diameter, bool symmetric, const EvalOptions& o) {
    ++score.targets;
    mssd_found.resize(o.mssd_fractions.size(), 0);
    if (!e) return;
    const double limit = o.correct_fraction * diameter;
    if (e->add_s < limit) {
      ++score.found_add_s;
      rotations.push_back(e->rotation_deg);
      translations.push_back(e->translation_mm);
    }
    if (e->add < limit) ++score.found_add;
    if ((symmetric ? e->add_s : e->add) < limit) ++score.found_add_or_s;
    for (std::size_t k = 0; k < o.mssd_fractions.size(); ++k) mssd_found[k] += e->mssd < o.mssd_fractions[k] * diameter;
  }

  static double mean(const std::vector<double>& v) {
    return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  }
  static double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  }

  Score finish(const EvalOptions& o) const {
    Score s = score;
    if (s.targets > 0 && !o.mssd_fractions.empty()) {
      double sum = 0;
      for (int f : mssd_found) sum += static_cast<double>(f) / s.targets;
      s.mssd_recall = sum / static_cast<double>(o.mssd_fractions.size());
    }
    s.mean_rotation_deg = mean(rotations);
    s.median_rotation_deg = median(rotations);
    s.mean_translation_mm = mean(translations);
    s.median_translation_mm = median(translations);
    return s;
  }
};

}  // namespace

EvalReport evaluate(const BopDataset& ds, const std::map<int, std::vector<Eigen::Vector3f>>& model_points,
                    std::span<const BopResult> results, const EvalOptions& o) {
  // The objects that matter: those with ground truth or estimates.
  std::set<int> ids;
  for (const BopImage& im : ds.images)
    for (const GroundTruthPose& g : im.gt) ids.insert(g.obj_id);
  EvalReport report;
  report.estimates.resize(results.size());
  const std::vector<bool> part = results_taking_part(results, o.targets);
  std::set<std::pair<int, int>> known_images;
  for (const BopImage& im : ds.images) known_images.insert({im.scene_id, im.im_id});
  std::map<std::pair<int, int>, std::vector<const BopResult*>> by_image;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const BopResult& r = results[i];
    const bool known = known_images.count({r.scene_id, r.im_id}) > 0;
    report.estimates[i].taking_part = part[i];
    if (known && !part[i]) {
      report.estimates[i].in_split = true;
      ++report.beyond_targets;
      continue;
    }
    by_image[{r.scene_id, r.im_id}].push_back(&r);
    if (known) ids.insert(r.obj_id);
  }
  // With targets, the objects each image's targets name; the others' ground truths are no targets.
  std::map<std::pair<int, int>, std::set<int>> listed;
  if (o.targets)
    for (const BopTarget& t : *o.targets) listed[{t.scene_id, t.im_id}].insert(t.obj_id);
  const auto is_target = [&](const BopImage& im, std::size_t g) {
    if (im.gt_info.size() == im.gt.size() && im.gt_info[g].visib_fract < o.min_visib_fract) return false;
    if (!o.targets) return true;
    const auto l = listed.find({im.scene_id, im.im_id});
    return l != listed.end() && l->second.count(im.gt[g].obj_id) > 0;
  };

  std::map<int, ObjectData> objects;
  for (int id : ids) {
    const auto points = model_points.find(id);
    if (points == model_points.end() || points->second.empty()) throw Error(fmt::format("eval: no model for object {}", id));
    ObjectData& data = objects[id];
    data.points = thin(points->second, o.max_model_points);
    ObjectScale scale = object_scale(ds.models, id, o.symmetry_step);
    data.diameter_m = scale.diameter_m;
    data.symmetries = std::move(scale.symmetries);
    if (!(data.diameter_m > 0)) data.diameter_m = diameter_of(data.points);
    if (!(data.diameter_m > 0)) throw Error(fmt::format("eval: object {} has no size", id));
  }

  Tally total;
  std::map<int, Tally> per_object, per_scene;
  double time_sum = 0;
  std::size_t matched_results = 0;
  for (const BopImage& im : ds.images) {
    ++report.images;
    const auto found = by_image.find({im.scene_id, im.im_id});
    const std::vector<const BopResult*> none;
    std::vector<const BopResult*> estimates = found == by_image.end() ? none : found->second;
    matched_results += estimates.size();
    if (!estimates.empty() && estimates.front()->time_s >= 0) {
      ++report.images_timed;
      time_sum += estimates.front()->time_s;
    }
    std::stable_sort(estimates.begin(), estimates.end(), [](const BopResult* a, const BopResult* b) { return a->score > b->score; });
    // Pair as the BOP toolkit matches: by decreasing score, each estimate takes the unpaired ground
    // truth of its object with the lowest ADD-S, if that is below the threshold. One with none is
    // wrong and takes nothing, so that a wrong pose cannot keep a right one of lower score from the
    // object it would find. A wrong estimate's errors are reported against the nearest ground truth
    // of its object, paired or not, to say how far off it was.
    std::vector<std::optional<Errors>> errors_of_gt(im.gt.size());
    for (const BopResult* e : estimates) {
      const ObjectData& object = objects.at(e->obj_id);
      const double limit = o.correct_fraction * object.diameter_m;
      std::optional<std::size_t> free, nearest;
      double free_add_s = 0, nearest_add_s = 0;
      for (std::size_t g = 0; g < im.gt.size(); ++g) {
        if (im.gt[g].obj_id != e->obj_id) continue;
        const double add_s = add_s_error(e->T_camera_object, im.gt[g].T_camera_object, object.points);
        if (!nearest || add_s < nearest_add_s) nearest = g, nearest_add_s = add_s;
        if (!errors_of_gt[g] && (!free || add_s < free_add_s)) free = g, free_add_s = add_s;
      }
      const bool correct = free && free_add_s < limit;
      const std::optional<std::size_t> best = correct ? free : nearest;
      const double best_add_s = correct ? free_add_s : nearest_add_s;
      const bool target = best && is_target(im, *best);
      EstimateOutcome& outcome = report.estimates[static_cast<std::size_t>(e - results.data())];
      outcome.in_split = true;
      outcome.paired = best.has_value();
      outcome.target = target;
      if (target || !correct) {
        outcome.counted = true;
        for (Tally* t : {&total, &per_object[e->obj_id], &per_scene[im.scene_id]}) {
          ++t->score.estimates;
          t->score.false_positives += correct ? 0 : 1;
        }
      }
      if (!best) continue;
      const Transform& truth = im.gt[*best].T_camera_object;
      Errors err;
      err.add_s = best_add_s;
      err.add = add_error(e->T_camera_object, truth, object.points);
      err.mssd = mssd_error(e->T_camera_object, truth, object.points, object.symmetries);
      err.rotation_deg = rotation_error_deg(e->T_camera_object.linear(), truth.linear());
      err.translation_mm = 1000.0 * (e->T_camera_object.translation() - truth.translation()).norm();
      if (correct) errors_of_gt[*best] = err;
      outcome.add_s_m = err.add_s;
      outcome.add_m = err.add;
      outcome.mssd_m = err.mssd;
      outcome.correct_add_s = correct;
      outcome.correct_add = correct && err.add < limit;
    }
    for (std::size_t g = 0; g < im.gt.size(); ++g) {
      if (!is_target(im, g)) continue;
      const int id = im.gt[g].obj_id;
      const Errors* e = errors_of_gt[g] ? &*errors_of_gt[g] : nullptr;
      const ObjectData& object = objects.at(id);
      for (Tally* t : {&total, &per_object[id], &per_scene[im.scene_id]}) t->add_target(e, object.diameter_m, object.symmetries.size() > 1, o);
    }
  }
  report.ignored_estimates = static_cast<int>(results.size() - matched_results) - report.beyond_targets;
  report.total = total.finish(o);

  // The precision-recall curve: counted estimates by decreasing score, a point where the score
  // changes (and at the last), so that equal scores enter together.
  std::vector<std::pair<double, bool>> scored;  // score, correct
  for (std::size_t i = 0; i < results.size(); ++i) {
    const EstimateOutcome& e = report.estimates[i];
    if (e.counted) scored.emplace_back(results[i].score, e.correct_add_s && e.target);
  }
  std::stable_sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  int correct = 0;
  for (std::size_t k = 0; k < scored.size(); ++k) {
    correct += scored[k].second;
    if (k + 1 < scored.size() && scored[k + 1].first == scored[k].first) continue;
    const int n = static_cast<int>(k + 1);
    report.pr_curve.push_back({scored[k].first, n, correct,
                               report.total.targets ? static_cast<double>(correct) / report.total.targets : 0.0,
                               static_cast<double>(correct) / n});
  }
  report.mean_time_s = report.images_timed ? time_sum / report.images_timed : 0.0;
  for (const auto& [id, t] : per_object) report.per_object[id] = t.finish(o);
  for (const auto& [id, t] : per_scene) report.per_scene[id] = t.finish(o);
  return report;
}

}  // namespace viewpose
