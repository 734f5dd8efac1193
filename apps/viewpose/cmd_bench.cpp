// `viewpose bench`: the whole pipeline over many frames, timed per stage. By default on a generated
// seed experiment (the built-in jug at 0.75-1.50 m, its database built in the same run); with
// --dataset on a BOP split against a given database. Prints median, 90th and 95th percentile and
// the frames per second; with ground truth also how many poses were right, so that speed is never
// bought with accuracy unseen.
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "camera_flags.hpp"
#include "commands.hpp"
#include "process_memory.hpp"
#include "progress.hpp"
#include "scene_input.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/stopwatch.hpp"
#include "viewpose/core/threads.hpp"
#include "viewpose/eval/metrics.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/recognize/recognizer.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/simulate/scaled_database.hpp"
#include "viewpose/simulate/scene.hpp"

namespace viewpose::cli {

namespace {

// A frame as the camera delivers it: its conversion to a cloud is timed with the rest. A scene file
// comes as a frame already made, as `viewpose recognize` makes it.
struct BenchFrame {
  DepthImage depth;
  CameraIntrinsics K;
  std::vector<GroundTruthPose> gt;
  std::optional<Frame> ready;
};

// N processes that do nothing but spin, for as long as this lives: the machine a robot's computer
// is, with other work on its cores. They die with their parent (PR_SET_PDEATHSIG), killed or not.
class BusyProcesses {
 public:
  explicit BusyProcesses(int n) {
    const pid_t parent = getpid();
    for (int i = 0; i < n; ++i) {
      const pid_t pid = fork();
      if (pid < 0) throw Error(fmt::format("bench: --load: cannot start a busy process: {}", std::strerror(errno)));
      if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent) _exit(0);  // the parent died before the line above could take effect
        volatile std::uint64_t spin = 0;
        for (;;) spin = spin + 1;
      }
      pids_.push_back(pid);
    }
  }
  ~BusyProcesses() {
    for (const pid_t pid : pids_) kill(pid, SIGKILL);
    for (const pid_t pid : pids_) waitpid(pid, nullptr, 0);
  }
  BusyProcesses(const BusyProcesses&) = delete;
  BusyProcesses& operator=(const BusyProcesses&) = delete;

 private:
  std::vector<pid_t> pids_;
};

// The setting: one object at 0.75-1.50 m, turned to evenly spaced yaws at each distance.
std::vector<BenchFrame> seed_frames(const ObjectModel& object, int count) {
  SeedExperimentOptions setup;
  setup.distances_m = {0.75, 1.00, 1.25, 1.50};
  setup.orientations = (count + 3) / 4;
  const CameraIntrinsics K = CameraIntrinsics::kinect_v1();
  const SimDataset scenes = make_seed_experiment(object, K, setup, 7);
  std::vector<BenchFrame> frames;
  // Interleave the distances, so that a shorter run still covers all of them.
  for (std::size_t k = 0; k < static_cast<std::size_t>(setup.orientations); ++k) {
    for (const SimScene& scene : scenes.scenes) {
      if (frames.size() >= static_cast<std::size_t>(count)) break;
      const SimulatedFrame f = simulate_image(scenes, scene.images[k], SensorModel::kinect_v1(), 100 * scene.scene_id + k);
      frames.push_back({f.depth, K, f.gt, {}});
    }
  }
  return frames;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

// Resident memory now (not the peak): what a long run must keep flat.
double current_rss_mib() {
  std::ifstream statm("/proc/self/statm");
  double pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return pages_resident * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports kilobytes
}

}  // namespace

void add_bench_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::string dataset, split = "test", models_dir = "models", db, json;
    std::vector<std::string> scenes;
    CameraFlags camera;
    int frames = 100, objects = 1, distinct = 0, block = 0, load = 0;
    double deadline_ms = 0;
    bool no_split = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "Time the whole pipeline over many frames: per-stage median and percentiles, frames per second, accuracy");
  cmd->add_option("--frames", o->frames, "Frames to run (the generated seed experiment, or the first N of the dataset)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--dataset", o->dataset, "BOP dataset folder (default: a generated seed experiment of the built-in jug)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--scene", o->scenes,
                  "Scene files, as `recognize` reads them (PCD or PLY clouds, depth PNGs with --camera or --intrinsics; "
                  "repeat, or give several) to run instead of a dataset, with --db; no ground truth, so every "
                  "detection is counted, not scored")
      ->check(CLI::ExistingFile)
      ->excludes("--dataset");
  cmd->add_option("--load", o->load,
                  "Start this many busy processes of its own for the timed frames: the pipeline's times on a machine "
                  "that is doing other things")
      ->check(CLI::Range(0, 64));
  cmd->add_option("--split", o->split, "Split folder")->capture_default_str();
  cmd->add_option("--models-dir", o->models_dir, "Folder of models_info.json, under the dataset")->capture_default_str();
  cmd->add_option("--db", o->db, "View database (required with --dataset; default: built from the jug in this run)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--objects", o->objects,
                  "Grow the database to this many objects: copies of its own with reshaped histograms, to measure "
                  "matching and memory at scale (a detection of a copy counts as the original)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_flag("--no-split", o->no_split, "Do not split clusters in which nothing is found");
  cmd->add_option("--deadline-ms", o->deadline_ms, "Per frame: stop trying poses after this long (0: no limit)")
      ->check(CLI::Range(0.0, 1e7));
  cmd->add_option("--distinct", o->distinct,
                  "Make only this many distinct frames and cycle through them (a long run without simulating each frame)")
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--block", o->block,
                  "Report every this many frames: median and p95 time, resident memory (is a long run steady?)")
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--json", o->json, "Also write the numbers as JSON to this file (with each frame's total time, total_ms, and poses tried, hypotheses)");
  o->camera.add_to(*cmd);
  cmd->callback([o, &exit_code] {
    if (!o->dataset.empty() && o->db.empty()) throw Error("bench: --dataset needs --db");
    if (!o->scenes.empty() && o->db.empty()) throw Error("bench: --scene needs --db");
    ViewDatabase db;
    double db_build_ms = 0, db_load_ms = 0;
    if (!o->db.empty()) {  // what a process run per file pays before its first frame
      const auto t = Clock::now();
      // (The pair tables only where the default source casts votes.)
      db = ViewDatabase::load(o->db, database_load_options(RecognizerOptions{}));
      db_load_ms = ms_since(t);
    }
    std::vector<BenchFrame> frames;
    std::string source;
    // The frames made (or read): all of them, or with --distinct that many, cycled through.
    const int to_make = o->distinct > 0 ? std::min(o->distinct, o->frames) : o->frames;
    if (!o->scenes.empty()) {
      for (std::size_t i = 0; i < o->scenes.size() && frames.size() < static_cast<std::size_t>(to_make); ++i) {
        Frame frame = load_scene(o->scenes[i], o->camera);
        frames.push_back({{}, frame.K, {}, std::move(frame)});
      }
      source = fmt::format("{} scene file{}", frames.size(), frames.size() == 1 ? "" : "s");
    } else if (o->dataset.empty()) {
      const ObjectModel jug{1, "jug", make_jug()};
      if (o->db.empty()) {
        const auto t = Clock::now();
        db = build_view_database(std::span(&jug, 1), DatabaseParams{});
        db_build_ms = ms_since(t);
      }
      fmt::print(stderr, "simulating {} frames of the jug at 0.75-1.50 m...\n", to_make);
      frames = seed_frames(jug, to_make);
      source = "seed experiment (jug, 0.75-1.50 m, simulated Kinect v1)";
    } else {
      const BopDataset ds = open_bop_dataset(o->dataset, o->split, {o->models_dir});
      for (const auto& note : ds.notes) fmt::print(stderr, "viewpose: note: {}\n", note);
      const std::size_t n = std::min(ds.images.size(), static_cast<std::size_t>(to_make));
      for (std::size_t i = 0; i < n; ++i) {
        const BopFrame bf = load_bop_frame(ds.images[i]);
        frames.push_back({bf.depth, bf.K, ds.images[i].gt, {}});
      }
      source = fmt::format("{} ({}, {} images)", o->dataset, o->split, n);
    }
    if (frames.empty()) throw Error("bench: no frames to run");
    const std::size_t originals = db.objects.size();
    if (o->objects > 1) {
      fmt::print(stderr, "growing the database to {} objects...\n", o->objects);
      db = scaled_database(db, static_cast<std::size_t>(o->objects), 11);
    }
    RecognizerOptions options;
    options.split.enabled = !o->no_split;
    options.run.deadline_ms = o->deadline_ms;
    const auto t_prepare = Clock::now();
    const Recognizer recognizer(db, options);
    const double prepare_ms = ms_since(t_prepare);

    struct Series {
      const char* name;
      std::vector<double> ms;
    };
    std::vector<Series> stages = {{"frame", {}}, {"downsample", {}}, {"segment", {}}, {"normals", {}}, {"vfh", {}},
                                  {"match", {}}, {"crh", {}},        {"icp", {}},     {"verify", {}},  {"split", {}},
                                  {"total", {}}};
    std::vector<double> hypotheses, repeats, per_hypothesis_ms, steps_per_hypothesis, match_per_region_ms;
    std::size_t targets = 0, found = 0, found_add = 0, wrong = 0, cut_short = 0;
    std::vector<std::size_t> failed_frames;  // a pose missed or a wrong detection: worth looking at
    // With --distinct, --frames runs cycle through the frames made; without, each frame runs once.
    const std::size_t runs = o->distinct > 0 ? static_cast<std::size_t>(o->frames) : frames.size();
    // The per-frame numbers are kept for the percentiles: their room is taken now, so that the
    // resident memory reported per block is the pipeline's, not these lists growing.
    for (Series& s : stages) s.ms.reserve(runs);
    hypotheses.reserve(runs);
    per_hypothesis_ms.reserve(runs);
    match_per_region_ms.reserve(runs);
    nlohmann::json blocks = nlohmann::json::array();
    std::size_t detections = 0;
    {
      const BusyProcesses load(o->load);
      ProgressBar bar("bench", runs);
      for (std::size_t run = 0; run < runs; ++run) {
        const std::size_t i = run % frames.size();
        Recognition r;
        double frame_ms = 0;
        if (frames[i].ready) {
          r = recognizer.recognize(*frames[i].ready);
        } else {
          DepthImage depth = frames[i].depth;  // as a camera hands over a fresh buffer
          const auto start = Clock::now();
          const Frame frame = frame_from_depth(std::move(depth), frames[i].K);
          frame_ms = ms_since(start);
          r = recognizer.recognize(frame);
        }
        detections += r.detections.size();
        const StageTimes& t = r.times;
        const double values[] = {frame_ms, t.downsample_ms, t.segment_ms, t.normals_ms, t.vfh_ms, t.match_ms,
                                 t.crh_ms,   t.icp_ms,        t.verify_ms,  t.split_ms,     t.total_ms + frame_ms};
        for (std::size_t s = 0; s < stages.size(); ++s) stages[s].ms.push_back(values[s]);
        hypotheses.push_back(static_cast<double>(r.hypotheses));
        repeats.push_back(static_cast<double>(r.repeats));
        cut_short += r.cut_short ? 1 : 0;
        if (r.hypotheses > 0) per_hypothesis_ms.push_back((t.icp_ms + t.verify_ms) / static_cast<double>(r.hypotheses));
        if (r.hypotheses > 0) steps_per_hypothesis.push_back(static_cast<double>(r.icp_steps) / static_cast<double>(r.hypotheses));
        if (r.regions > 0) match_per_region_ms.push_back(t.match_ms / static_cast<double>(r.regions));
        // Right: a detection of the same object within ADD-S 10 % of its diameter; anything else is wrong.
        targets += frames[i].gt.size();
        std::vector<char> paired(frames[i].gt.size(), 0);
        for (const Detection& d : r.detections) {
          const DatabaseObject& object = db.objects[d.object_index];
          const int original_id = db.objects[d.object_index % originals].id;  // copies follow their originals
          bool right = false;
          for (std::size_t g = 0; g < frames[i].gt.size() && !right; ++g) {
            if (paired[g] || frames[i].gt[g].obj_id != original_id) continue;
            right = add_s_error(d.T_camera_object, frames[i].gt[g].T_camera_object, object.model_points) <
                    0.1 * object.diameter_m;
            if (right) {
              paired[g] = 1;
              found_add += add_error(d.T_camera_object, frames[i].gt[g].T_camera_object, object.model_points) <
                           0.1 * object.diameter_m;
            }
          }
          found += right ? 1 : 0;
          wrong += right ? 0 : 1;
        }
        const std::size_t right_here = static_cast<std::size_t>(std::count(paired.begin(), paired.end(), 1));
        if ((right_here < frames[i].gt.size() || r.detections.size() > right_here) && run < frames.size()) failed_frames.push_back(i);
        bar.update(run + 1);
        if (o->block > 0 && (run + 1) % static_cast<std::size_t>(o->block) == 0) {
          const std::vector<double>& all = stages.back().ms;
          const std::vector<double> last(all.end() - o->block, all.end());
          const double rss = current_rss_mib();
          blocks.push_back({{"frames", run + 1}, {"median_ms", percentile(last, 0.5)}, {"p95_ms", percentile(last, 0.95)},
                            {"max_ms", percentile(last, 1.0)}, {"rss_mib", rss}});
          fmt::print(stderr, "\rframes {:>7}: median {:.2f} ms, p95 {:.2f} ms, max {:.1f} ms, resident {:.0f} MiB\n", run + 1,
                     percentile(last, 0.5), percentile(last, 0.95), percentile(last, 1.0), rss);
        }
      }
    }
    const double total_s = [&] {
      double s = 0;
      for (double v : stages.back().ms) s += v / 1000;
      return s;
    }();
    const double fps = static_cast<double>(runs) / total_s;
    fmt::print("{}: {} frames{}, {} thread{}{}, database of {} objects x {} views\n", source, runs,
               runs > frames.size() ? fmt::format(" ({} distinct, cycled)", frames.size()) : std::string(), thread_count(),
               thread_count() == 1 ? "" : "s", o->load > 0 ? fmt::format(", {} busy processes beside", o->load) : std::string(),
               db.objects.size(), db.views.size());
    fmt::print("OpenMP waits: {}\n", openmp_wait());
    fmt::print("malloc: GLIBC_TUNABLES {}\n", malloc_tunables());
    if (db_build_ms > 0) fmt::print("database build: {:.0f} ms\n", db_build_ms);
    if (db_load_ms > 0) fmt::print("database loaded in {:.1f} ms\n", db_load_ms);
    fmt::print("recognizer made in {:.0f} ms\n", prepare_ms);
    fmt::print("{:<12} {:>9} {:>9} {:>9} {:>9} {:>9}\n", "stage (ms)", "median", "p90", "p95", "max", "mean");
    nlohmann::json jstages;
    for (const Series& s : stages) {
      double mean = 0;
      for (double v : s.ms) mean += v / static_cast<double>(s.ms.size());
      const double med = percentile(s.ms, 0.5), p90 = percentile(s.ms, 0.9), p95 = percentile(s.ms, 0.95),
                   mx = percentile(s.ms, 1.0);
      fmt::print("{:<12} {:>9.2f} {:>9.2f} {:>9.2f} {:>9.2f} {:>9.2f}\n", s.name, med, p90, p95, mx, mean);
      jstages[s.name] = {{"median", med}, {"p90", p90}, {"p95", p95}, {"max", mx}, {"mean", mean}};
    }
    if (thread_count() > 1) {
      fmt::print("(a frame's clusters run side by side on the threads: each stage's time is summed over them, and the\n"
                 " stages may add up to more than the frame's total, which is its wall time)\n");
    }
    const double hyp_med = percentile(hypotheses, 0.5), repeats_med = percentile(repeats, 0.5), per_hyp = percentile(per_hypothesis_ms, 0.5),
                 steps_per_hyp = percentile(steps_per_hypothesis, 0.5), match_per_region = percentile(match_per_region_ms, 0.5);
    fmt::print("{:.1f} frames per second; {:.0f} hypotheses per frame (median; {:.0f} of them refined onto a pose already "
               "refused, not verified again), ICP + verify {:.2f} ms and {:.1f} ICP steps per hypothesis, matching {:.2f} ms "
               "per cluster (medians)\n",
               fps, hyp_med, repeats_med, per_hyp, steps_per_hyp, match_per_region);
    if (!o->scenes.empty()) fmt::print("detections: {} in {} frames (no ground truth)\n", detections, runs);
    if (targets > 0) {
      fmt::print("poses right (ADD-S < 10 % of the diameter): {} of {} ({:.1f} %), the right way round too (ADD): {}; "
                 "wrong detections: {}\n", found, targets, 100.0 * static_cast<double>(found) / static_cast<double>(targets),
                 found_add, wrong);
      if (!failed_frames.empty())
        fmt::print("frames with a pose missed or wrong (0-based): {}\n", fmt::join(failed_frames, " "));
    }
    if (o->deadline_ms > 0) fmt::print("frames cut short by the {:.1f} ms deadline: {}\n", o->deadline_ms, cut_short);
    const double rss = peak_rss_mib();
    fmt::print("peak resident memory: {:.0f} MiB\n", rss);
    if (!o->json.empty()) {
      const nlohmann::json j = {{"source", source}, {"frames", runs}, {"distinct_frames", frames.size()}, {"blocks", blocks}, {"threads", thread_count()}, {"openmp_wait", openmp_wait()}, {"glibc_tunables", malloc_tunables()},
                                {"objects", db.objects.size()}, {"views", db.views.size()},
                                {"db_build_ms", db_build_ms}, {"db_load_ms", db_load_ms}, {"prepare_ms", prepare_ms}, {"load_processes", o->load}, {"detections", detections}, {"stages_ms", jstages}, {"fps", fps},
                                {"hypotheses_median", hyp_med}, {"repeats_median", repeats_med}, {"icp_verify_per_hypothesis_ms", per_hyp}, {"icp_steps_per_hypothesis", steps_per_hyp}, {"match_per_cluster_ms", match_per_region},
                                {"targets", targets}, {"right", found}, {"right_add", found_add}, {"wrong", wrong}, {"failed_frames", failed_frames}, {"cut_short", cut_short},
                                {"peak_rss_mib", rss}, {"total_ms", stages.back().ms}, {"hypotheses", hypotheses}};
      write_file_atomic(o->json, j.dump(2) + "\n");
    }
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
