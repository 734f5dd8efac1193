// `viewpose simulate`: synthetic depth frames with exact ground truth, written as a BOP dataset.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "camera_flags.hpp"
#include "commands.hpp"
#include "model_args.hpp"
#include "progress.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/image_png.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/sensor/kinect_raw.hpp"
#include "viewpose/simulate/bop_writer.hpp"
#include "viewpose/visualize/image.hpp"

namespace viewpose::cli {

namespace fs = std::filesystem;

void write_contact_sheet(const fs::path& dataset, const std::string& split, const fs::path& out, std::size_t count) {
  // Read back through the BOP reader, as any user of the dataset would.
  const BopDataset ds = open_bop_dataset(dataset, split);
  std::vector<const BopImage*> chosen;
  int last_scene = -1;
  for (const auto& im : ds.images) {  // the first image of every scene first
    if (im.scene_id != last_scene) chosen.push_back(&im);
    last_scene = im.scene_id;
  }
  for (const auto& im : ds.images) {
    if (chosen.size() >= count) break;
    if (std::find(chosen.begin(), chosen.end(), &im) == chosen.end()) chosen.push_back(&im);
  }
  chosen.resize(std::min(chosen.size(), count));
  std::vector<DepthImage> frames;
  std::vector<float> all;
  for (const BopImage* im : chosen) {
    frames.push_back(load_bop_frame(*im).depth);
    for (float z : frames.back().depth_m) if (std::isfinite(z)) all.push_back(z);
  }
  if (all.empty()) throw Error(fmt::format("{}: no valid depth to show", dataset.string()));
  std::sort(all.begin(), all.end());
  const float near = all[all.size() / 50], far = all[all.size() * 49 / 50];
  std::vector<RgbImage> tiles;
  for (const auto& f : frames) tiles.push_back(colourize_depth(f, near, far));
  write_rgb_png(out, tile_images(tiles, 4));
}

namespace {

// The unknown objects of a room: the user's --distractor meshes, and the built-in shapes that are
// not known objects (a known one among the distractors would be an object with no ground truth).
std::vector<std::shared_ptr<const TriangleMesh>> distractor_meshes(const std::vector<std::string>& models,
                                                                   const std::vector<std::string>& distractors, LengthUnit unit) {
  for (const std::string& d : distractors) {
    if (std::find(models.begin(), models.end(), d) != models.end()) {
      throw Error(fmt::format("simulate: {} is a --model and a --distractor; a known object has ground truth", d));
    }
  }
  std::vector<std::string> names = distractors;
  for (const std::string& shape : shape_names()) {
    if (std::find(models.begin(), models.end(), shape) == models.end()) names.push_back(shape);
  }
  std::vector<std::shared_ptr<const TriangleMesh>> out;
  for (ObjectModel& m : load_models(names, unit)) out.push_back(std::make_shared<const TriangleMesh>(std::move(m.mesh)));
  return out;
}

}  // namespace

void add_simulate_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::string preset = "seed-experiment";
    std::string out;
    std::vector<std::string> models{"jug"};
    std::string unit = "m";
    std::uint64_t seed = 1;
    bool no_noise = false;
    int orientations = 20;
    std::vector<double> distances{0.75, 1.00, 1.25, 1.50, 2.00};
    int images = 20;
    bool room = false;
    int rooms = 4;
    double empty_fraction = 0.2;
    std::vector<std::string> distractors;
    std::string contact_sheet, fakenect;
    CameraFlags camera;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("simulate", "Render synthetic depth frames with exact ground truth as a BOP dataset");
  cmd->add_option("--preset", o->preset,
                  "seed-experiment (the thesis's set-up: one object at each distance), clutter (2-5 objects touching "
                  "on a table) or room (known objects among unknown ones on a room's table, seen from a few heights, "
                  "and frames with no known object)")
      ->check(CLI::IsMember({"seed-experiment", "clutter", "room"}))
      ->capture_default_str();
  cmd->add_option("-o,--out", o->out, "Dataset folder to write")->required();
  cmd->add_option("--model", o->models, "Objects: jug, box, can, mug, or mesh files (repeat for several)")
      ->capture_default_str();
  cmd->add_option("--unit", o->unit, "Unit of mesh files: m, mm or cm")->check(CLI::IsMember({"m", "mm", "cm"}))->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of every random choice")->capture_default_str();
  cmd->add_flag("--no-noise", o->no_noise, "Write the rendered depth without the sensor model");
  cmd->add_option("--orientations", o->orientations, "seed-experiment: orientations per distance")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--distances", o->distances, "seed-experiment: distances in metres")->delimiter(',')->capture_default_str();
  cmd->add_option("--images", o->images, "clutter, room: number of images (room: dealt to the rooms in turn)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_flag("--room", o->room,
                "seed-experiment, clutter: put the table in a room (a finite table on legs, walls and floor 1.5-4 m away, "
                "furniture, unknown objects on and off the table, none in front of a known one); the known objects' "
                "poses stay as without it");
  cmd->add_option("--rooms", o->rooms, "room: number of rooms (one scene each)")->check(CLI::Range(1, 1000))->capture_default_str();
  cmd->add_option("--empty-fraction", o->empty_fraction, "room: share of the frames with no known object in them")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--distractor", o->distractors,
                  "room, --room: a mesh file (or built-in shape) of an unknown object to scatter too (repeat for several; "
                  "--unit applies). The built-in shapes that are not a --model are scattered anyway");
  cmd->add_option("--contact-sheet", o->contact_sheet, "Also write a PNG of a few frames, to look at");
  cmd->add_option("--fakenect", o->fakenect,
                  "Also write the frames, in order, as a fakenect recording (raw Kinect disparity) to replay through "
                  "libfreenect: viewpose live --source freenect with FAKENECT_PATH=DIR");
  o->camera.add_to(*cmd);
  cmd->footer(
      "The camera defaults to a Kinect v1 / Xtion at VGA (fx = fy = 525). Rooms (--preset room, --room) put only the "
      "--models in the ground truth; walls, furniture and unknown objects are background, and visib_fract counts what "
      "they hide. docs/SENSOR_MODEL.md says what the sensor model does at a room's 3-4 m.");
  cmd->callback([o, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    CameraIntrinsics K = CameraIntrinsics::kinect_v1();
    if (const auto cam = o->camera.camera()) {
      K = cam->K;
      if (K.width == 0) {
        K.width = 640;
        K.height = 480;
      }
    }
    const std::vector<ObjectModel> objects = load_models(o->models, parse_length_unit(o->unit));
    if (o->room && o->preset == "room") throw Error("simulate: --room is for seed-experiment and clutter; the room preset has rooms already");
    const bool rooms = o->room || o->preset == "room";
    if (!rooms && !o->distractors.empty()) throw Error("simulate: --distractor needs --preset room or --room");
    RoomOptions room;
    if (rooms) room.distractor_meshes = distractor_meshes(o->models, o->distractors, parse_length_unit(o->unit));
    SimDataset ds;
    if (o->preset == "seed-experiment") {
      if (objects.size() != 1) throw Error("simulate: the seed experiment takes exactly one --model");
      SeedExperimentOptions se;
      se.orientations = o->orientations;
      se.distances_m = o->distances;
      ds = make_seed_experiment(objects[0], K, se, o->seed);
    } else if (o->preset == "clutter") {
      ClutterOptions cl;
      cl.images = o->images;
      ds = make_clutter(objects, K, cl, o->seed);
    } else {
      RoomPresetOptions ro;
      ro.rooms = o->rooms;
      ro.images = o->images;
      ro.empty_fraction = o->empty_fraction;
      ro.room = room;
      ds = make_room_scenes(objects, K, ro, o->seed);
    }
    if (o->room) put_in_room(ds, room, o->seed);
    BopWriteOptions wo;
    wo.seed = o->seed;
    if (o->no_noise) wo.sensor = SensorModel::ideal();
    std::size_t total = 0;
    for (const auto& s : ds.scenes) total += s.images.size();
    {
      ProgressBar bar("simulate", total);
      wo.progress = [&bar](std::size_t done, std::size_t) { bar.update(done); };
      write_bop_dataset(o->out, ds, wo);
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print("wrote {}: {} scene(s), {} images of {} object(s), {} ({:.1f} s, {:.0f} ms per image)\n", o->out,
               ds.scenes.size(), total, objects.size(), o->no_noise ? "noise-free" : "Kinect v1 sensor model", seconds,
               1000.0 * seconds / static_cast<double>(std::max<std::size_t>(total, 1)));
    for (const auto& s : ds.scenes) fmt::print("  scene {:06d}: {} images, {}\n", s.scene_id, s.images.size(), s.description);
    if (!o->fakenect.empty()) {
      // The frames as written (millimetres), so that the dataset's ground truth holds for the recording.
      const BopDataset written = open_bop_dataset(o->out, "test");
      std::vector<DepthImage> frames;
      for (const BopImage& image : written.images) frames.push_back(load_bop_frame(image).depth);
      write_fakenect_recording(o->fakenect, frames);
      fmt::print("fakenect recording: {} ({} frames at 30 a second; the ground truth is {}'s, in the same order)\n",
                 o->fakenect, frames.size(), o->out);
    }
    if (!o->contact_sheet.empty()) {
      write_contact_sheet(o->out, "test", o->contact_sheet, 8);
      fmt::print("contact sheet: {}\n", o->contact_sheet);
    }
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
