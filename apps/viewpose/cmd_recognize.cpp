// `viewpose recognize` (one scene) and `viewpose bop` (every image of a BOP dataset split).
#include <chrono>
#include <cmath>
#include <future>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "camera_flags.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "scene_input.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/bop_results.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/core/threads.hpp"
#include "viewpose/io/image_png.hpp"
#include "viewpose/io/ply.hpp"
#include "viewpose/io/recognition_json.hpp"
#include "viewpose/eval/metrics.hpp"
#include "viewpose/pose/confidence.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/visualize/overlay.hpp"

namespace viewpose::cli {

namespace {

// A scene or image id from a json file bop wrote, checked before it is narrowed: json's get<int>
// of 1e60 is a conversion C++ leaves undefined.
int json_id(const nlohmann::json& x) {
  const double d = x.get<double>();
  if (!(d >= 0 && d <= 1e9) || d != std::floor(d)) throw Error(fmt::format("{} is not a scene or image id", x.dump()));
  return static_cast<int>(d);
}

struct RecognizeFlags {
  std::string db;
  bool keep_best = false;
  bool no_split = false;
  std::size_t matches = 20;
  std::size_t budget = RecognizerOptions{}.match.max_hypotheses;
  std::size_t screen = RecognizerOptions{}.match.prescreen;
  std::string source{pose_source_name(RecognizerOptions{}.match.source)};
  double deadline_ms = 0;
  double min_score = -1;  // < 0: the recognizer's default
  bool no_times = false;
  void add_to(CLI::App& cmd) {
    cmd.add_option("--db", db, "View database (viewpose db build)")->required()->check(CLI::ExistingFile);
    cmd.add_flag("--keep-best", keep_best, "Try every hypothesis and keep the best, not the first that passes");
    cmd.add_flag("--no-split", no_split,
                 "Do not split clusters in which nothing is found at concave creases (touching objects); faster");
    cmd.add_option("--matches", matches, "Nearest views tried per cluster")->check(CLI::Range(1, 1000))->capture_default_str();
    cmd.add_option("--budget", budget,
                   "Starting poses refined and verified per cluster at most, best first (0: every view's every roll, "
                   "as the thesis did; slower, and rarely finds more)")
        ->check(CLI::Range(0, 1000000))
        ->capture_default_str();
    cmd.add_option("--screen", screen,
                   "Starting poses per cluster screened by a short ICP, which orders them for --budget by where they "
                   "lead (the first few are tried in coarse fit order before it; 0: coarse fit order only); one the camera "
                   "sees past where it led, or that it led where it led one refined already, is not refined, and spends "
                   "its share of --budget")
        ->check(CLI::Range(0, 1000000))
        ->capture_default_str();
    cmd.add_option("--source", source,
                   "Where starting poses come from: vfh (each cluster's nearest database views, as the thesis), ppf "
                   "(point pair feature votes over the cluster: touching and half-hidden objects; about 7 ms per "
                   "object and cluster more), both (the views' poses first; where none passes, the votes'), or touching (as both, "
                   "but votes only in what a detection leaves of its region, where neither its views' poses nor its convex parts' "
                   "pass: objects touching it)")
        ->check(CLI::IsMember(std::vector<std::string>(std::begin(kPoseSourceNames), std::end(kPoseSourceNames))))
        ->capture_default_str();
    cmd.add_option("--deadline-ms", deadline_ms,
                   "Stop trying poses after this long per frame and report what is verified, marked cut short (0: no limit)")
        ->check(CLI::Range(0.0, 1e7));
    cmd.add_option("--min-score", min_score,
                   "Report only poses whose score (the estimated probability that the pose is right) reaches this; "
                   "lower finds more and is wrong more often (default: the threshold that kept 98 % of the poses "
                   "right on the simulated rooms the confidence was fit on, docs/CONFIDENCE.md)")
        ->check(CLI::Range(0.0, 1.0));
    cmd.add_flag("--no-times", no_times,
                 "Write no run times into the output files (a BOP CSV's time is -1, the JSON has none), so that they "
                 "depend on the inputs alone, byte for byte, whatever the thread count");
  }
  // The pair tables are read only where votes will be cast (for one frame, only once they are).
  DatabaseLoadOptions load_options(FramesToServe frames) const { return database_load_options(options(), frames); }
  RecognizerOptions options() const {
    RecognizerOptions o;
    o.accept.keep_best = keep_best;
    o.split.enabled = !no_split;
    o.match.per_object = matches;
    o.match.max_hypotheses = budget;
    o.match.prescreen = screen;
    o.match.source = pose_source_from_name(source);
    o.run.deadline_ms = deadline_ms;
    if (min_score >= 0) o.accept.min_confidence = min_score;
    return o;
  }
};

// Yaw about z, then pitch about y, then roll about x (R = Rz Ry Rx), in degrees.
Eigen::Vector3d yaw_pitch_roll_deg(const Eigen::Matrix3d& R) {
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double yaw = std::atan2(R(1, 0), R(0, 0)), roll = std::atan2(R(2, 1), R(2, 2));
  return Eigen::Vector3d(yaw, pitch, roll) * 180.0 / std::numbers::pi;
}

}  // namespace

void print_recognition(const Recognition& r, double min_score) {
  if (r.detections.empty()) {
    fmt::print("no known object found ({} clusters, {} poses tried)\n", r.clusters, r.hypotheses);
    // Why not: the nearest a pose came. A box's face seen alone, or a small patch, scores low
    // (docs/CONFIDENCE.md); a user whose scene holds no look-alikes may take a lower --min-score.
    if (const auto& b = r.best_below_min_score) {
      const Eigen::Vector3d t = b->T_camera_object.translation();
      fmt::print("  the most confident pose below --min-score {:.3f}: {} (id {}) at ({:.3f}, {:.3f}, {:.3f}) m, score {:.3f}\n",
                 min_score, b->object_name, b->object_id, t.x(), t.y(), t.z(), b->score);
    }
  }
  for (const Detection& d : r.detections) {
    const Eigen::Vector3d t = d.T_camera_object.translation();
    const Eigen::Vector3d ypr = yaw_pitch_roll_deg(d.T_camera_object.linear());
    // The margin: how far the pose stood above its best half-turned rival (none passing: the score).
    fmt::print("{} (id {}): position ({:.3f}, {:.3f}, {:.3f}) m, yaw/pitch/roll ({:.1f}, {:.1f}, {:.1f}) deg, score {:.2f}, "
               "margin {:.2f}, match rank {}\n", d.object_name, d.object_id, t.x(), t.y(), t.z(), ypr.x(), ypr.y(), ypr.z(),
               d.score, d.verification.score - d.runner_up_score, d.match_rank);
  }
  if (r.cut_short) fmt::print("cut short by the deadline: views, parts or checks were left untried\n");
  const StageTimes& s = r.times;
  fmt::print("time {:.1f} ms: downsample {:.1f}, segment {:.1f}, normals {:.1f}, vfh {:.1f}, match {:.1f}, crh {:.1f}, "
             "icp {:.1f}, verify {:.1f}, split {:.1f}\n", s.total_ms, s.downsample_ms, s.segment_ms, s.normals_ms, s.vfh_ms,
             s.match_ms, s.crh_ms, s.icp_ms, s.verify_ms, s.split_ms);
}

void add_recognize_command(CLI::App& app, int& exit_code) {
  struct Options {
    RecognizeFlags flags;
    CameraFlags camera;
    std::string scene, json, overlay, aligned;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("recognize", "Find the database's objects in one scene and estimate their poses");
  o->flags.add_to(*cmd);
  cmd->add_option("scene", o->scene, "Depth PNG (with --camera or --intrinsics), PCD or PLY cloud")->required();
  o->camera.add_to(*cmd);
  cmd->add_option("--json", o->json, "Write detections and per-stage times (ms) as JSON");
  cmd->add_option("--overlay", o->overlay, "Write a PNG of the depth with each detected model drawn in colour");
  cmd->add_option("--aligned", o->aligned, "Write a PLY of the scene with the aligned model points");
  cmd->callback([o, &exit_code] {
    // The database and the scene are read side by side: most of a one-frame process's start-up.
    // (Should the database fail, its error is the one said; the scene's reading is waited for.)
    // (OpenMP's thread count is per thread: the reading thread is given --threads too.)
    auto scene = std::async(std::launch::async, [&, threads = thread_count()] {
      set_thread_count(threads);
      return load_scene(o->scene, o->camera);
    });
    const ViewDatabase db = ViewDatabase::load(o->flags.db, o->flags.load_options(FramesToServe::one));
    const Frame frame = scene.get();
    // One frame: ICP grids the database does not store fill only where its hypotheses look,
    // instead of whole before it (about 0.1 s an object).
    RecognizerOptions options = o->flags.options();
    options.run.fill_grids_at_start = false;
    const Recognizer recognizer(db, options);
    const Recognition r = recognizer.recognize(frame);
    print_recognition(r, options.accept.min_confidence);
    if (!o->json.empty()) {
      nlohmann::json j = recognition_json(r, !o->flags.no_times);
      j["scene"] = o->scene;
      write_file_atomic(o->json, j.dump(1) + "\n");
    }
    std::vector<OverlayItem> items;
    for (const Detection& d : r.detections) {
      for (const auto& obj : db.objects) {
        if (obj.id == d.object_id) items.push_back({&obj.mesh, d.T_camera_object, 0.5 * obj.diameter_m});
      }
    }
    if (!o->overlay.empty()) write_rgb_png(o->overlay, draw_overlay(frame.depth, frame.K, items));
    if (!o->aligned.empty()) {
      PointCloud out;
      for (const auto& p : frame.cloud.points) {
        if (!p.allFinite()) continue;
        out.points.push_back(p);
        out.rgba.push_back(0xff909090u);
      }
      for (std::size_t i = 0; i < r.detections.size(); ++i) {
        const auto c = palette(i);
        for (const auto& obj : db.objects) {
          if (obj.id != r.detections[i].object_id) continue;
          for (const auto& p : obj.model_points) {
            out.points.push_back((r.detections[i].T_camera_object * p.cast<double>()).cast<float>());
            out.rgba.push_back(0xff000000u | (std::uint32_t{c[0]} << 16) | (std::uint32_t{c[1]} << 8) | c[2]);
          }
        }
      }
      out.width = static_cast<int>(out.points.size());
      write_ply(o->aligned, out, PlyEncoding::BinaryLittleEndian);
    }
    exit_code = 0;
  });
}

namespace {

// `viewpose bop`'s record of the images it has finished, beside the results (OUT.progress): BOP19
// rows cannot say which images had no detection, so the list is kept apart. It is rewritten,
// atomically, after the results it vouches for, every few images; a run resumed from it drops any
// row of an image it does not list (written just before an interruption) and does that image again.
struct BopProgress {
  std::string dataset, split, db, targets;
  std::set<std::pair<int, int>> done;  // (scene_id, im_id)

  nlohmann::json to_json() const {
    nlohmann::json images = nlohmann::json::array();
    for (const auto& [scene, im] : done) images.push_back({scene, im});
    return {{"dataset", dataset}, {"split", split}, {"db", db}, {"targets", targets}, {"done", images}};
  }
  static BopProgress read(const std::filesystem::path& path) {
    const auto bytes = read_file_bytes(path, std::size_t{256} << 20);
    BopProgress p;
    try {
      const auto j = nlohmann::json::parse(bytes.begin(), bytes.end());
      p.dataset = j.at("dataset").get<std::string>();
      p.split = j.at("split").get<std::string>();
      p.db = j.at("db").get<std::string>();
      p.targets = j.value("targets", std::string());
      for (const auto& e : j.at("done")) p.done.insert({json_id(e.at(0)), json_id(e.at(1))});
    } catch (const nlohmann::json::exception& e) {
      throw Error(fmt::format("{}: not a progress file viewpose bop wrote ({})", path.string(), e.what()));
    }
    return p;
  }
};

}  // namespace

namespace {

// The BOP19 task's answer for one image: of the objects it names, at most its instance count of
// each, the highest scores first; the rest dropped.
void keep_targets(Recognition& r, const std::map<int, int>& inst_count) {
  std::stable_sort(r.detections.begin(), r.detections.end(),
                   [](const Detection& a, const Detection& b) { return a.score > b.score; });
  std::map<int, int> kept;
  std::erase_if(r.detections, [&](const Detection& d) {
    const auto it = inst_count.find(d.object_id);
    return it == inst_count.end() || ++kept[d.object_id] > it->second;
  });
}

// One JSON line per pose verification passed, labelled by its ADD-S to the nearest ground truth of
// its object in the image (a share of the object's diameter; null when none is there).
std::string hypotheses_json(const std::vector<VerifiedHypothesis>& heard, const ViewDatabase& db, const BopImage& im) {
  std::string lines;
  for (const VerifiedHypothesis& h : heard) {
    const DatabaseObject& object = db.objects[h.object_index];
    std::optional<double> add_s;
    double visib = -1;
    for (std::size_t g = 0; g < im.gt.size(); ++g) {
      if (im.gt[g].obj_id != object.id) continue;
      const double e = add_s_error(h.T_camera_object, im.gt[g].T_camera_object, object.model_points) / object.diameter_m;
      if (!add_s || e < *add_s) {
        add_s = e;
        visib = g < im.gt_info.size() ? im.gt_info[g].visib_fract : -1;
      }
    }
    nlohmann::ordered_json features = nlohmann::ordered_json::object();  // in the order of confidence_features()
    const ConfidenceFeatures f = confidence_features(h.verification);
    for (std::size_t k = 0; k < f.size(); ++k) features[std::string(confidence_feature_names()[k])] = f[k];
    nlohmann::ordered_json line = {{"scene_id", im.scene_id}, {"im_id", im.im_id}, {"obj_id", object.id},
                           {"confidence", h.confidence}, {"fit_score", h.verification.score}, {"features", features},
                           {"verification", verification_json(h.verification)},
                           {"add_s_rel", add_s ? nlohmann::ordered_json(*add_s) : nlohmann::ordered_json(nullptr)}, {"gt_visib", visib}};
    lines += line.dump() + "\n";
  }
  return lines;
}

}  // namespace

namespace {

// Per image (scene_id, im_id), the objects to report and at most how many of each.
using WantedObjects = std::map<std::pair<int, int>, std::map<int, int>>;

// The BOP19 task: only the images the targets file lists stay in `ds`; each with its objects.
WantedObjects restrict_to_targets(BopDataset& ds, const std::string& targets) {
  WantedObjects wanted;
  for (const BopTarget& t : read_bop_targets(targets)) wanted[{t.scene_id, t.im_id}][t.obj_id] = t.inst_count;
  std::set<std::pair<int, int>> in_split;
  for (const BopImage& im : ds.images) in_split.insert({im.scene_id, im.im_id});
  for (const auto& [image, objects] : wanted) {
    if (!in_split.count(image)) {
      throw Error(fmt::format("{}: lists scene {} image {}, which split '{}' does not have", targets, image.first,
                              image.second, ds.split));
    }
  }
  std::erase_if(ds.images, [&](const BopImage& im) { return !wanted.count({im.scene_id, im.im_id}); });
  return wanted;
}

// --resume: the images an earlier run of the same inputs finished, with their rows and detail
// lines; a progress file of other inputs is an error, none means starting afresh.
void resume_run(const std::filesystem::path& progress_path, const std::string& out, const std::string& details,
                std::size_t images, BopProgress& progress, std::vector<BopResult>& results,
                std::vector<std::string>& detail_lines) {
  if (!std::filesystem::exists(progress_path)) {
    fmt::print(stderr, "bop: nothing to resume ({} is absent): starting afresh\n", progress_path.string());
    return;
  }
  const BopProgress before = BopProgress::read(progress_path);
  if (before.dataset != progress.dataset || before.split != progress.split || before.db != progress.db ||
      before.targets != progress.targets) {
    throw Error(fmt::format("{}: written for {} ({}) with {}{}, not this run's; start afresh without --resume",
                            progress_path.string(), before.dataset, before.split, before.db,
                            before.targets.empty() ? std::string() : " and targets " + before.targets));
  }
  progress.done = before.done;
  // Rows and detail lines of images the progress file vouches for; any other is done again.
  if (std::filesystem::exists(out)) {
    for (const BopResult& r : read_bop_results(out))
      if (progress.done.count({r.scene_id, r.im_id})) results.push_back(r);
  }
  if (!details.empty() && std::filesystem::exists(details)) {
    const auto bytes = read_file_bytes(details);
    std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    while (!text.empty()) {
      const std::size_t end = text.find('\n');
      const std::string_view line = text.substr(0, end);
      text = end == std::string_view::npos ? std::string_view{} : text.substr(end + 1);
      try {
        const auto j = nlohmann::json::parse(line);
        if (progress.done.count({json_id(j.at("scene_id")), json_id(j.at("im_id"))})) detail_lines.emplace_back(line);
      } catch (const nlohmann::json::exception&) {
        // A line cut short by the interruption: its image is done again.
      }
    }
  }
  fmt::print(stderr, "bop: resuming: {} of {} images already done\n", progress.done.size(), images);
}

// One --details line: the image's recognition and, unless `seconds` < 0 (--no-times), its time.
std::string detail_line(const Recognition& r, const BopImage& im, double seconds) {
  nlohmann::json line = recognition_json(r, seconds >= 0);
  line["scene_id"] = im.scene_id;
  line["im_id"] = im.im_id;
  if (seconds >= 0) line["seconds"] = seconds;
  return line.dump();
}

}  // namespace

void add_bop_command(CLI::App& app, int& exit_code) {
  struct Options {
    RecognizeFlags flags;
    std::string dataset, split = "test", out, models_dir = "models", details, targets, hypotheses;
    bool resume = false;
    std::size_t images = 0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("bop", "Run recognition on every image of a BOP dataset split; write BOP19 CSV");
  o->flags.add_to(*cmd);
  cmd->add_option("--dataset", o->dataset, "BOP dataset folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--split", o->split, "Split folder")->capture_default_str();
  cmd->add_option("--models-dir", o->models_dir, "Folder of models_info.json, under the dataset")->capture_default_str();
  cmd->add_option("-o,--out", o->out, "Results CSV")->required();
  cmd->add_option("--details", o->details,
                  "Also write one JSON line per image: its detections (in the CSV's order, with match rank and "
                  "verification) and per-stage times in ms");
  cmd->add_option("--targets", o->targets,
                  "BOP19 targets (the dataset's test_targets_bop19.json): do only the images it lists, and report for "
                  "each only the objects it names, at most its instance count of each, the best first (the BOP19 task). "
                  "Without it every image, any object, any number")
      ->check(CLI::ExistingFile);
  cmd->add_option("--hypotheses", o->hypotheses,
                  "For fitting the confidence model (scripts/fit-confidence.py): write one JSON line for every pose that "
                  "passed verification's bounds, with its evidence, its confidence and its ADD-S to the nearest ground "
                  "truth of its object (as a share of the diameter). Use with --keep-best to hear of every one");
  cmd->add_flag("--resume", o->resume,
                "Carry on an interrupted run: keep the images OUT.progress lists as done, do the rest");
  cmd->add_option("--images", o->images, "Do at most this many images in this run (then --resume does more)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 40));
  cmd->callback([o, &exit_code] {
    const ViewDatabase db = ViewDatabase::load(o->flags.db, o->flags.load_options(FramesToServe::many));
    BopDataset ds = open_bop_dataset(o->dataset, o->split, {o->models_dir});
    for (const auto& note : ds.notes) fmt::print(stderr, "viewpose: note: {}\n", note);
    // The BOP19 task: per image, the objects to find and how many of each.
    const WantedObjects wanted = o->targets.empty() ? WantedObjects{} : restrict_to_targets(ds, o->targets);
    // Every pose that passes verification's bounds, heard of while an image is recognized.
    std::vector<VerifiedHypothesis> heard;
    RecognizerOptions options = o->flags.options();
    if (!o->hypotheses.empty()) {
      if (o->resume) throw Error("bop: --hypotheses cannot be resumed; run it afresh");
      options.accept.on_verified = [&heard](const VerifiedHypothesis& h) { heard.push_back(h); };
    }
    std::string hypothesis_lines;
    const Recognizer recognizer(db, options);
    const std::filesystem::path progress_path = o->out + ".progress";
    BopProgress progress{std::filesystem::absolute(o->dataset).lexically_normal().string(), ds.split,
                         std::filesystem::absolute(o->flags.db).lexically_normal().string(),
                         o->targets.empty() ? std::string() : std::filesystem::absolute(o->targets).lexically_normal().string(), {}};
    std::vector<BopResult> results;
    std::vector<std::string> detail_lines;
    if (o->resume) resume_run(progress_path, o->out, o->details, ds.images.size(), progress, results, detail_lines);
    const auto checkpoint = [&] {
      // Results first, then the list that vouches for them.
      write_bop_results(o->out, results);
      if (!o->details.empty()) {
        std::string text;
        for (const auto& line : detail_lines) text += line + "\n";
        write_file_atomic(o->details, text);
      }
      write_file_atomic(progress_path, progress.to_json().dump() + "\n");
    };
    std::size_t detections = 0, ran = 0;
    double total_ms = 0;
    auto last_checkpoint = std::chrono::steady_clock::now();
    {
      ProgressBar bar("bop", ds.images.size());
      for (std::size_t i = 0; i < ds.images.size(); ++i) {
        const BopImage& im = ds.images[i];
        if (progress.done.count({im.scene_id, im.im_id})) continue;
        if (o->images > 0 && ran >= o->images) break;
        const auto start = std::chrono::steady_clock::now();
        const BopFrame bf = load_bop_frame(im);
        heard.clear();
        Recognition r = recognizer.recognize(frame_from_depth(bf.depth, bf.K));
        if (!o->hypotheses.empty()) hypothesis_lines += hypotheses_json(heard, db, im);
        if (const auto it = wanted.find({im.scene_id, im.im_id}); it != wanted.end()) keep_targets(r, it->second);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        total_ms += 1000 * seconds;
        ++ran;
        for (const Detection& d : r.detections) {
          results.push_back({im.scene_id, im.im_id, d.object_id, d.score, d.T_camera_object, o->flags.no_times ? -1.0 : seconds});
          ++detections;
        }
        if (!o->details.empty()) detail_lines.push_back(detail_line(r, im, o->flags.no_times ? -1.0 : seconds));
        progress.done.insert({im.scene_id, im.im_id});
        // A checkpoint every two seconds: an interruption loses at most that much work.
        if (std::chrono::steady_clock::now() - last_checkpoint > std::chrono::seconds(2)) {
          checkpoint();
          last_checkpoint = std::chrono::steady_clock::now();
        }
        bar.update(i + 1);
      }
    }
    // The rows in dataset order, whatever order the runs came in.
    std::stable_sort(results.begin(), results.end(), [](const BopResult& a, const BopResult& b) {
      return std::pair(a.scene_id, a.im_id) < std::pair(b.scene_id, b.im_id);
    });
    checkpoint();
    if (!o->hypotheses.empty()) write_file_atomic(o->hypotheses, hypothesis_lines);
    const bool complete = progress.done.size() >= ds.images.size();
    if (complete) std::filesystem::remove(progress_path);  // nothing left to resume
    fmt::print("{}: {} detections in {} images, {:.1f} ms per image{}\n", o->out, detections, ran,
               total_ms / static_cast<double>(std::max<std::size_t>(ran, 1)),
               complete ? std::string()
                        : fmt::format("; {} of {} images done, --resume does the rest", progress.done.size(), ds.images.size()));
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
