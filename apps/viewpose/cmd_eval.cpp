// viewpose eval: score BOP19 results against a BOP dataset's ground truth.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "model_args.hpp"
#include "viewpose/eval/evaluate.hpp"
#include "viewpose/io/file.hpp"

namespace viewpose::cli {

namespace {

nlohmann::json to_json(const Score& s) {
  return {{"targets", s.targets},
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
}

void print_row(const std::string& name, const Score& s) {
  fmt::print("{:<14} {:>7} {:>8.1f} {:>8.1f} {:>8.1f} {:>8.1f} {:>6} {:>9.2f} {:>9.2f} {:>9.1f} {:>9.1f}\n", name, s.targets,
             100 * s.recall_add_s(), 100 * s.recall_add(), 100 * s.recall_add_or_s(), 100 * s.mssd_recall, s.false_positives, s.mean_rotation_deg,
             s.median_rotation_deg, s.mean_translation_mm, s.median_translation_mm);
}

}  // namespace

void add_eval_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, split = "test", models_dir = "models", results, json;
    double fraction = 0.1;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("eval", "Score BOP19 results against a BOP dataset's ground truth");
  cmd->add_option("--dataset", o->dataset, "BOP dataset folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--split", o->split, "Split folder")->capture_default_str();
  cmd->add_option("--models-dir", o->models_dir, "Folder of the obj_NNNNNN.ply models and models_info.json, under the dataset")
      ->capture_default_str();
  cmd->add_option("--results", o->results, "BOP19 CSV (viewpose bop -o)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--threshold", o->fraction, "ADD and ADD-S: correct below this share of the object's diameter")
      ->check(CLI::Range(0.001, 1.0))
      ->capture_default_str();
  cmd->add_option("--json", o->json, "Write the scores as JSON");
  cmd->callback([o, &exit_code] {
    const BopDataset ds = open_bop_dataset(o->dataset, o->split, {o->models_dir});
    const std::vector<BopResult> results = read_bop_results(o->results);
    std::map<int, std::vector<Eigen::Vector3f>> points;
    for (ObjectModel& m : load_bop_models(ds.root / o->models_dir)) points[m.id] = std::move(m.mesh.vertices);
    EvalOptions options;
    options.correct_fraction = o->fraction;
    const EvalReport r = evaluate(ds, points, results, options);

    fmt::print("{} images, {} estimates; recall in %, errors of the estimates correct under ADD-S\n", r.images, results.size());
    fmt::print("{:<14} {:>7} {:>8} {:>8} {:>8} {:>8} {:>6} {:>9} {:>9} {:>9} {:>9}\n", "", "targets", "ADD-S", "ADD", "ADD(-S)", "MSSD",
               "FP", "rot mean", "rot med", "mm mean", "mm med");
    for (const auto& [id, s] : r.per_object) print_row(fmt::format("object {}", id), s);
    if (r.per_scene.size() > 1) {
      for (const auto& [id, s] : r.per_scene) print_row(fmt::format("scene {}", id), s);
    }
    print_row("all", r.total);
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
                          {"ignored_estimates", r.ignored_estimates}, {"all", to_json(r.total)}};
      for (const auto& [id, s] : r.per_object) j["per_object"][std::to_string(id)] = to_json(s);
      for (const auto& [id, s] : r.per_scene) j["per_scene"][std::to_string(id)] = to_json(s);
      j["estimates"] = nlohmann::json::array();
      for (std::size_t i = 0; i < r.estimates.size(); ++i) {
        const EstimateOutcome& e = r.estimates[i];
        j["estimates"].push_back({{"scene_id", results[i].scene_id}, {"im_id", results[i].im_id},
                                  {"obj_id", results[i].obj_id}, {"score", results[i].score},
                                  {"in_split", e.in_split}, {"paired", e.paired}, {"target", e.target},
                                  {"add_s_mm", 1000 * e.add_s_m}, {"add_mm", 1000 * e.add_m}, {"mssd_mm", 1000 * e.mssd_m},
                                  {"correct_add_s", e.correct_add_s}, {"correct_add", e.correct_add}});
      }
      write_file_atomic(o->json, j.dump(2) + "\n");
    }
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
