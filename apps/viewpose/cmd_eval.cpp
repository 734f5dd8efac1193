// viewpose eval: score BOP19 results against a BOP dataset's ground truth.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>

#include "commands.hpp"
#include "model_args.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/eval/bop_scores.hpp"
#include "viewpose/eval/evaluate.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose::cli {

namespace {

// The BOP average recalls beside a row's other scores (`bop` null when the row has no valid
// ground truth under BOP's rules).
void add_bop(nlohmann::json& j, const BopRecall* bop) {
  j["ar"] = bop ? bop->ar() : 0.0;
  j["ar_vsd"] = bop ? bop->ar_vsd : 0.0;
  j["ar_mssd"] = bop ? bop->ar_mssd : 0.0;
  j["ar_mspd"] = bop ? bop->ar_mspd : 0.0;
  j["bop_targets"] = bop ? bop->targets : 0;
}

const BopRecall* find_row(const std::map<int, BopRecall>& rows, int id) {
  const auto it = rows.find(id);
  return it == rows.end() ? nullptr : &it->second;
}

nlohmann::json to_json(const Score& s, const BopRecall* bop, int images) {
  nlohmann::json j = {{"targets", s.targets},
          {"recall_add_s", s.recall_add_s()},
          {"recall_add", s.recall_add()},
          {"recall_add_or_s", s.recall_add_or_s()},
          {"recall_mssd", s.mssd_recall},
          {"found_add_s", s.found_add_s},
          {"found_add", s.found_add},
          {"estimates", s.estimates},
          {"false_positives", s.false_positives},
          {"rotation_error_deg", {{"mean", s.mean_rotation_deg}, {"median", s.median_rotation_deg}}},
          {"translation_error_mm", {{"mean", s.mean_translation_mm}, {"median", s.median_translation_mm}}}};
  if (images > 0) j["false_positives_per_image"] = static_cast<double>(s.false_positives) / images;
  add_bop(j, bop);
  return j;
}

void print_bop_row(const std::string& name, const BopRecall& r) {
  fmt::print("{:<14} {:>7} {:>8.1f} {:>8.1f} {:>8.1f} {:>8.1f}\n", name, r.targets, 100 * r.ar(), 100 * r.ar_vsd,
             100 * r.ar_mssd, 100 * r.ar_mspd);
}

// The curve at about every tenth of the estimates, and at its end.
void print_pr_curve(const std::vector<PrecisionRecallPoint>& curve) {
  if (curve.empty()) return;
  fmt::print("precision-recall over the detection score (correct: ADD-S below the threshold, paired one-to-one):\n");
  const int n = curve.back().estimates;
  std::size_t next = 0;
  for (int tenth = 1; tenth <= 10; ++tenth) {
    std::size_t k = next;
    while (k + 1 < curve.size() && curve[k].estimates * 10 < tenth * n) ++k;
    const PrecisionRecallPoint& p = curve[k];
    fmt::print("  score >= {:<10.4g} {:>5} estimates  recall {:>5.1f} %  precision {:>5.1f} %\n", p.score, p.estimates,
               100 * p.recall, 100 * p.precision);
    next = k + 1;
    if (next >= curve.size()) break;
  }
}

void print_row(const std::string& name, const Score& s) {
  fmt::print("{:<14} {:>7} {:>8.1f} {:>8.1f} {:>8.1f} {:>8.1f} {:>6} {:>9.2f} {:>9.2f} {:>9.1f} {:>9.1f}\n", name, s.targets,
             100 * s.recall_add_s(), 100 * s.recall_add(), 100 * s.recall_add_or_s(), 100 * s.mssd_recall, s.false_positives, s.mean_rotation_deg,
             s.median_rotation_deg, s.mean_translation_mm, s.median_translation_mm);
}

}  // namespace

void add_eval_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, split = "test", models_dir, results, json, targets;
    double fraction = 0.1, vsd_delta_mm = 15;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("eval", "Score BOP19 results against a BOP dataset's ground truth");
  cmd->add_option("--dataset", o->dataset, "BOP dataset folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--split", o->split, "Split folder")->capture_default_str();
  cmd->add_option("--models-dir", o->models_dir,
                  "Folder of the obj_NNNNNN.ply models and models_info.json, under the dataset (default: models_eval "
                  "when the dataset has it, as the BOP toolkit scores, else models, or T-LESS's models_cad)");
  cmd->add_option("--results", o->results, "BOP19 CSV (viewpose bop -o)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--threshold", o->fraction, "ADD and ADD-S: correct below this share of the object's diameter")
      ->check(CLI::Range(0.001, 1.0))
      ->capture_default_str();
  cmd->add_option("--targets", o->targets,
                  "BOP19 targets (test_targets_bop19.json): only the listed objects are to be found, and of each only "
                  "its inst_count best estimates count; without it, every estimate counts (open mode)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--vsd-delta", o->vsd_delta_mm, "VSD visibility tolerance in mm (BOP19: 15; 5 for ITODD)")
      ->check(CLI::Range(0.001, 1000.0))
      ->capture_default_str();
  cmd->add_option("--json", o->json, "Write the scores as JSON");
  cmd->callback([o, &exit_code] {
    // By default the models the BOP toolkit scores with (models_eval, else what recognition reads:
    // models, or T-LESS's models_cad); a folder asked for by name, that one.
    const BopDataset ds = open_bop_dataset(o->dataset, o->split, {o->models_dir.empty() ? "models" : o->models_dir});
    if (o->models_dir.empty()) o->models_dir = ds.eval_models_dir;
    if (o->models_dir.empty()) {
      throw viewpose::Error(fmt::format("{}: no models folder (models/ or models_eval/ with obj_NNNNNN.ply, in mm): scoring needs "
                              "the meshes; copy the dataset's models in, or name a folder with --models-dir",
                              o->dataset));
    }
    std::vector<std::string> notes = ds.notes;
    const std::vector<BopResult> results = read_bop_results(o->results, &notes);
    for (const std::string& note : notes) fmt::print(stderr, "viewpose: note: {}\n", note);
    std::optional<std::vector<BopTarget>> targets;
    if (!o->targets.empty()) targets = read_bop_targets(o->targets);
    std::map<int, std::vector<Eigen::Vector3f>> points;
    std::map<int, TriangleMesh> meshes;
    for (ObjectModel& m : load_bop_models(ds.root / o->models_dir)) {
      points[m.id] = m.mesh.vertices;
      meshes[m.id] = std::move(m.mesh);
    }
    EvalOptions options;
    options.correct_fraction = o->fraction;
    options.targets = targets;
    const EvalReport r = evaluate(ds, points, results, options);
    BopScoreOptions bop_options;
    bop_options.targets = targets;
    bop_options.vsd_delta_m = o->vsd_delta_mm / 1000.0;
    const BopScores bop = score_bop(ds, meshes, results, bop_options);

    fmt::print("{} images, {} estimates; recall in %, errors of the estimates correct under ADD-S\n", r.images, results.size());
    fmt::print("{:<14} {:>7} {:>8} {:>8} {:>8} {:>8} {:>6} {:>9} {:>9} {:>9} {:>9}\n", "", "targets", "ADD-S", "ADD", "ADD(-S)", "MSSD",
               "FP", "rot mean", "rot med", "mm mean", "mm med");
    for (const auto& [id, s] : r.per_object) print_row(fmt::format("object {}", id), s);
    if (r.per_scene.size() > 1) {
      for (const auto& [id, s] : r.per_scene) print_row(fmt::format("scene {}", id), s);
    }
    print_row("all", r.total);
    fmt::print("false positives: {:.2f} per image\n", r.false_positives_per_image());
    print_pr_curve(r.pr_curve);

    fmt::print("\nBOP19 average recall in % ({}; VSD delta {:g} mm, tau 5-50 % of the diameter; MSPD thresholds x {:.2f})\n",
               bop.targets_mode ? fmt::format("targets from {}", o->targets) : std::string("open mode: every estimate"),
               o->vsd_delta_mm, bop.mspd_scale);
    fmt::print("{:<14} {:>7} {:>8} {:>8} {:>8} {:>8}\n", "", "targets", "AR", "AR_VSD", "AR_MSSD", "AR_MSPD");
    for (const auto& [id, b] : bop.per_object) print_bop_row(fmt::format("object {}", id), b);
    if (bop.per_scene.size() > 1) {
      for (const auto& [id, b] : bop.per_scene) print_bop_row(fmt::format("scene {}", id), b);
    }
    print_bop_row("all", bop.total);
    if (r.beyond_targets > 0) {
      fmt::print("{} estimates beyond the targets (objects not listed, or past inst_count) took no part\n", r.beyond_targets);
    }
    if (r.images_timed > 0) {
      fmt::print("time: {:.1f} ms per image (mean over the {} images with estimates)\n", 1000 * r.mean_time_s, r.images_timed);
    }
    if (r.ignored_estimates > 0) {
      fmt::print(stderr, "{} estimates are for images not in the split and were ignored\n", r.ignored_estimates);
    }
    if (!o->json.empty()) {
      nlohmann::json j = {{"dataset", o->dataset}, {"split", o->split}, {"results", o->results},
                          {"threshold_fraction", o->fraction}, {"images", r.images},
                          {"images_timed", r.images_timed}, {"mean_time_ms", 1000 * r.mean_time_s},
                          {"ignored_estimates", r.ignored_estimates}, {"beyond_targets", r.beyond_targets},
                          {"all", to_json(r.total, &bop.total, r.images)}};
      // BOP's numbers at the top as well, with how they were made.
      add_bop(j, &bop.total);
      j["false_positives_per_image"] = r.false_positives_per_image();
      j["targets_file"] = o->targets.empty() ? nlohmann::json(nullptr) : nlohmann::json(o->targets);
      j["bop"] = {{"mode", bop.targets_mode ? "targets" : "open"},
                  {"estimates_used", bop.estimates_used},
                  {"vsd_delta_mm", o->vsd_delta_mm},
                  {"vsd_taus_fraction_of_diameter", bop_options.vsd_taus},
                  {"vsd_thresholds", bop_options.vsd_thresholds},
                  {"mssd_thresholds_fraction_of_diameter", bop_options.mssd_fractions},
                  {"mspd_thresholds_px", bop_options.mspd_px},
                  {"mspd_scale", bop.mspd_scale},
                  {"found_vsd", bop.total.found_vsd},
                  {"found_mssd", bop.total.found_mssd},
                  {"found_mspd", bop.total.found_mspd}};
      // An object with estimates but no valid ground truth has a row in `r`, not in `bop`: AR 0.
      for (const auto& [id, s] : r.per_object) j["per_object"][std::to_string(id)] = to_json(s, find_row(bop.per_object, id), 0);
      for (const auto& [id, s] : r.per_scene) j["per_scene"][std::to_string(id)] = to_json(s, find_row(bop.per_scene, id), 0);
      j["pr_curve"] = nlohmann::json::array();
      for (const PrecisionRecallPoint& p : r.pr_curve) {
        j["pr_curve"].push_back({{"score", p.score}, {"estimates", p.estimates}, {"correct", p.correct},
                                 {"recall", p.recall}, {"precision", p.precision}});
      }
      j["estimates"] = nlohmann::json::array();
      for (std::size_t i = 0; i < r.estimates.size(); ++i) {
        const EstimateOutcome& e = r.estimates[i];
        j["estimates"].push_back({{"scene_id", results[i].scene_id}, {"im_id", results[i].im_id},
                                  {"obj_id", results[i].obj_id}, {"score", results[i].score},
                                  {"in_split", e.in_split}, {"taking_part", e.taking_part}, {"counted", e.counted},
                                  {"paired", e.paired}, {"target", e.target},
                                  {"add_s_mm", 1000 * e.add_s_m}, {"add_mm", 1000 * e.add_m}, {"mssd_mm", 1000 * e.mssd_m},
                                  {"correct_add_s", e.correct_add_s}, {"correct_add", e.correct_add}});
      }
      write_file_atomic(o->json, j.dump(2) + "\n");
    }
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
