// `viewpose live`: recognition on a camera's stream (or a recording of one), frame after frame.
// A camera thread grabs frames (and records them, when asked) into a one-frame mailbox; the main
// thread recognizes the newest. Frames that arrive while one is being recognized replace each
// other and are counted as dropped. Ctrl-C (or SIGTERM) ends the run cleanly with a summary; a
// second Ctrl-C kills it.
#include <atomic>
#include <csignal>
#include <exception>
#include <memory>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "camera_flags.hpp"
#include "commands.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/stopwatch.hpp"
#include "viewpose/io/recognition_json.hpp"
#include "viewpose/recognize/frame.hpp"
#include "viewpose/sensor/depth_source.hpp"
#include "viewpose/sensor/latest_frame.hpp"

namespace viewpose::cli {

namespace {

std::atomic<bool> g_stop{false};

extern "C" void on_stop_signal(int signal) {
  g_stop = true;
  std::signal(signal, SIG_DFL);  // a second one ends the process at once
}

std::string one_line(const Recognition& r) {
  if (r.detections.empty()) return fmt::format("nothing found ({} clusters)", r.clusters);
  std::string out;
  for (const Detection& d : r.detections) {
    const Eigen::Vector3d t = d.T_camera_object.translation();
    out += fmt::format("{}{} at ({:.3f}, {:.3f}, {:.3f}) m, score {:.2f}", out.empty() ? "" : "; ", d.object_name, t.x(),
                       t.y(), t.z(), d.score);
  }
  return out;
}

}  // namespace

void add_live_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::string db, source, record;
    CameraFlags camera;
    bool json_lines = false, no_split = false;
    int frames = 0;
    double seconds = 0, stall_seconds = 5, deadline_ms = 0, min_score = -1;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("live", "Recognize objects in a depth camera's stream, frame after frame");
  cmd->add_option("--db", o->db, "View database (viewpose db build)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--source", o->source,
                  "freenect[:INDEX] (Kinect v1), openni2[:URI or FILE.oni] (Xtion, PrimeSense, Kinect), or "
                  "recording:DIR (a folder --record wrote)")
      ->required();
  o->camera.add_to(*cmd);
  cmd->add_flag("--json-lines", o->json_lines, "Print one JSON object per recognized frame instead of text");
  cmd->add_option("--record", o->record, "Also save every frame received, as a BOP scene folder (depth PNGs and scene_camera.json)");
  cmd->add_option("--frames", o->frames, "Stop after recognizing this many frames (default: until Ctrl-C or the recording ends)")
      ->check(CLI::Range(0, 1 << 30));
  cmd->add_option("--seconds", o->seconds, "Stop after this many seconds")->check(CLI::Range(0.0, 1e7));
  cmd->add_option("--stall-seconds", o->stall_seconds, "A camera that sends no frame for this long is an error")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  cmd->add_flag("--no-split", o->no_split, "Do not split clusters in which nothing is found (faster)");
  cmd->add_option("--deadline-ms", o->deadline_ms,
                  "Per frame: stop trying poses after this long and report what is verified, marked cut short (0: no limit)")
      ->check(CLI::Range(0.0, 1e7));
  cmd->add_option("--min-score", o->min_score,
                  "Report only poses whose score (the estimated probability that the pose is right) reaches this "
                  "(default: the threshold fit for 98 % precision, docs/CONFIDENCE.md)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->callback([o, &exit_code] {
    // From the start: a Ctrl-C while the database loads or the camera opens also ends cleanly.
    g_stop = false;
    std::signal(SIGINT, on_stop_signal);
    std::signal(SIGTERM, on_stop_signal);
    struct RestoreSignals {
      ~RestoreSignals() {
        std::signal(SIGINT, SIG_DFL);
        std::signal(SIGTERM, SIG_DFL);
      }
    } restore_signals;
    // (The pair tables only where the default source casts votes.)
    const ViewDatabase db = ViewDatabase::load(o->db, database_load_options(RecognizerOptions{}));
    RecognizerOptions options;
    options.split.enabled = !o->no_split;
    options.run.deadline_ms = o->deadline_ms;
    if (o->min_score >= 0) options.accept.min_confidence = o->min_score;
    const Recognizer recognizer(db, options);
    const std::unique_ptr<DepthSource> source = open_depth_source(o->source);
    CameraIntrinsics K = source->intrinsics();
    if (const auto cam = o->camera.camera()) {
      // The user's calibration; the image size stays the stream's.
      K.fx = cam->K.fx, K.fy = cam->K.fy, K.cx = cam->K.cx, K.cy = cam->K.cy;
      if (cam->K.width > 0 && (cam->K.width != K.width || cam->K.height != K.height)) {
        throw Error(fmt::format("live: the camera file is for {}x{} images, the stream gives {}x{}", cam->K.width,
                                cam->K.height, K.width, K.height));
      }
    }
    K.validate();
    std::unique_ptr<DepthRecorder> recorder;
    if (!o->record.empty()) recorder = std::make_unique<DepthRecorder>(o->record, K);
    fmt::print(stderr, "live: {} ({}x{}, fx {:.1f}); Ctrl-C to stop\n", source->description(), K.width, K.height, K.fx);

    LatestFrame mailbox;
    std::exception_ptr camera_error;
    bool source_ended = false;
    std::thread camera([&] {
      try {
        auto last_frame = Clock::now();
        while (!g_stop) {
          std::optional<DepthImage> depth = source->next(std::chrono::milliseconds(100));
          if (!depth) {
            if (source->ended()) break;
            if (ms_since(last_frame) > 1000.0 * o->stall_seconds) {
              throw Error(fmt::format("live: no frame from {} for {:.0f} s (unplugged?)", source->description(), o->stall_seconds));
            }
            continue;
          }
          last_frame = Clock::now();
          if (recorder) recorder->add(*depth);
          mailbox.put(std::move(*depth));
        }
        source_ended = source->ended();
      } catch (...) {
        camera_error = std::current_exception();
      }
      mailbox.close();
    });

    const auto start = Clock::now();
    std::size_t recognized = 0;
    try {
      while (!g_stop) {
        if (o->frames > 0 && recognized >= static_cast<std::size_t>(o->frames)) break;
        if (o->seconds > 0 && ms_since(start) >= 1000.0 * o->seconds) break;
        std::optional<DepthImage> depth = mailbox.take(std::chrono::milliseconds(200));
        if (!depth) {
          if (mailbox.closed()) break;
          continue;
        }
        const double t_s = ms_since(start) / 1000.0;
        const auto t0 = Clock::now();
        const Frame frame = frame_from_depth(std::move(*depth), K);
        const Recognition r = recognizer.recognize(frame);
        const double ms = ms_since(t0);
        ++recognized;
        if (o->json_lines) {
          nlohmann::json line = recognition_json(r);
          line["frame"] = recognized - 1;
          line["time_s"] = t_s;
          line["frame_ms"] = ms;
          line["received"] = mailbox.delivered();
          line["dropped"] = mailbox.dropped();
          fmt::print("{}\n", line.dump());
        } else {
          fmt::print("frame {} at {:.2f} s, {:.1f} ms: {}{}\n", recognized - 1, t_s, ms, one_line(r),
                     r.cut_short ? " (cut short)" : "");
        }
        std::fflush(stdout);
      }
    } catch (...) {
      g_stop = true;
      camera.join();
      throw;
    }
    const bool interrupted = g_stop;
    g_stop = true;  // the camera thread ends within its 100 ms wait
    camera.join();
    if (recorder) recorder->flush();
    if (camera_error) std::rethrow_exception(camera_error);

    const double seconds = ms_since(start) / 1000.0;
    const std::uint64_t received = mailbox.delivered(), dropped = mailbox.dropped();
    const char* why = interrupted ? "stopped" : source_ended ? "the recording ended" : "done";
    fmt::print(stderr, "live: {} after {:.1f} s: {} frames received ({:.1f} a second), {} recognized ({:.1f} a second), {} dropped{}\n",
               why, seconds, received, seconds > 0 ? static_cast<double>(received) / seconds : 0.0, recognized,
               seconds > 0 ? static_cast<double>(recognized) / seconds : 0.0, dropped,
               recorder ? fmt::format("; recorded {} frames in {}", recorder->frames(), o->record) : std::string());
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
