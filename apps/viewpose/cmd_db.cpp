// `viewpose db build` and `viewpose db info`: the view database of the objects to recognize.
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "camera_flags.hpp"
#include "commands.hpp"
#include "model_args.hpp"
#include "progress.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/database/view_database.hpp"
#include "viewpose/io/pcd.hpp"
#include "viewpose/io/ply.hpp"

namespace viewpose::cli {

namespace fs = std::filesystem;

void print_database(const fs::path& path, const ViewDatabase& db) {
  const auto& p = db.params;
  std::uintmax_t bytes = fs::exists(path) ? fs::file_size(path) : 0;
  fmt::print("{}: viewpose view database, format version {}, {:.1f} MB\n", path.string(), ViewDatabase::kFormatVersion,
             static_cast<double>(bytes) / 1e6);
  fmt::print("  views:     {} (a mesh object gets {}: view sphere with {} subdivision(s), camera {:.2f} m from the centre)\n",
             db.views.size(), 20 << (2 * p.subdivisions), p.subdivisions, p.distance_m);
  fmt::print("  camera:    {}x{}, fx {} fy {} cx {} cy {}\n", p.camera.width, p.camera.height, p.camera.fx, p.camera.fy,
             p.camera.cx, p.camera.cy);
  fmt::print("  describe:  voxel {} mm, ICP copy {} mm, normal radius {} mm, VFH {}\n", p.voxel_m * 1000, p.icp_voxel_m * 1000,
             p.describe.normals.radius_m * 1000, p.describe.vfh.pcl_compatible ? "PCL-compatible" : "corrected");
  std::size_t drawn = 0, grids = 0, tables = 0;
  for (const DatabaseObject& o : db.objects) {
    drawn += o.drawn_mesh.triangles.empty() ? 0 : 1;
    grids += o.nearest_cells.empty() ? 0 : 1;
    tables += o.pair_table ? 1 : 0;
  }
  const std::size_t grid_bytes = stored_grid_bytes(db);
  fmt::print("  prepared:  {} of {} objects with a drawing mesh ({} mm), {} with a filled ICP grid ({} mm cells, {:.1f} MB)\n",
             drawn, db.objects.size(), p.drawn_mesh_error_m * 1000, grids, p.grid_cell_m * 1000, static_cast<double>(grid_bytes) / 1e6);
  fmt::print("             {} with a point pair table (sampled at {} of the diameter, {} angle bins, {:.1f} MB)\n", tables,
             p.ppf.sample_fraction, p.ppf.angle_bins, static_cast<double>(stored_pair_table_bytes(db)) / 1e6);
  fmt::print("  objects:   {}\n", db.objects.size());
  for (std::size_t o = 0; o < db.objects.size(); ++o) {
    std::size_t views = 0, points = 0;
    for (const auto& v : db.views) {
      if (v.object != o) continue;
      ++views;
      points += v.described_points;
    }
    fmt::print("    id {:>4}  {:<24} diameter {:6.1f} mm, {} views, {} points per view on average{}\n", db.objects[o].id,
               db.objects[o].name, db.objects[o].diameter_m * 1000, views, views ? points / views : 0,
               db.objects[o].mesh.triangles.empty() ? " (scanned)" : "");
    const Symmetries& sym = db.objects[o].symmetries;
    if (sym.continuous.size() >= 2) {
      fmt::print("              symmetric: any rotation about its centre (a ball)\n");
    } else if (!sym.empty()) {
      std::string text;
      for (const ContinuousSymmetry& c : sym.continuous) {
        text += fmt::format("any turn about axis ({:.2f}, {:.2f}, {:.2f})", c.axis.x(), c.axis.y(), c.axis.z());
      }
      if (!sym.discrete.empty()) {
        text += fmt::format("{}{} discrete symmetr{}", text.empty() ? "" : ", plus ", sym.discrete.size(),
                            sym.discrete.size() == 1 ? "y" : "ies");
        for (const Transform& S : sym.discrete) {
          const Eigen::AngleAxisd aa(S.linear());
          text += fmt::format(" [{:.0f} deg about ({:.2f}, {:.2f}, {:.2f})]", aa.angle() * 180 / M_PI, aa.axis().x(),
                              aa.axis().y(), aa.axis().z());
        }
      }
      fmt::print("              symmetric: {}; poses are reported in one canonical form\n", text);
    }
  }
}

void add_db_command(CLI::App& app, int& exit_code) {
  CLI::App* db_cmd = app.add_subcommand("db", "Build or inspect a view database");
  db_cmd->require_subcommand(1);

  struct BuildOptions {
    std::vector<std::string> models;
    std::string bop_models;
    std::string unit = "m";
    std::string out;
    int views = 80;
    double distance = 1.0;
    bool corrected_vfh = false;
    CameraFlags camera;
  };
  auto b = std::make_shared<BuildOptions>();
  CLI::App* build = db_cmd->add_subcommand("build", "Render every object from a view sphere and describe each view");
  build->add_option("models", b->models, "Objects: jug, box, can, mug, or mesh files (OBJ, STL, PLY, ...)");
  build->add_option("--bop-models", b->bop_models, "A BOP models/ folder: every obj_NNNNNN.ply, with id NNNNNN");
  build->add_option("--unit", b->unit, "Unit of the mesh files: m, mm or cm")->check(CLI::IsMember({"m", "mm", "cm"}))->capture_default_str();
  build->add_option("-o,--out", b->out, "Database file to write")->required();
  build->add_option("--views", b->views, "Views per object: 80 (the thesis) or 320")->check(CLI::IsMember({20, 80, 320}))->capture_default_str();
  build->add_option("--distance", b->distance, "Camera distance from the object's centre, metres")->check(CLI::Range(0.2, 10.0))->capture_default_str();
  build->add_flag("--corrected-vfh", b->corrected_vfh, "Use the corrected VFH (full bin ranges) instead of PCL's");
  b->camera.add_to(*build);
  build->callback([b, &exit_code] {
    const auto start = std::chrono::steady_clock::now();
    std::vector<ObjectModel> models = load_models(b->models, parse_length_unit(b->unit));
    if (!b->bop_models.empty()) {
      for (ObjectModel& m : load_bop_models(b->bop_models)) models.push_back(std::move(m));
    }
    if (models.empty()) throw Error("db build: no objects (name models or give --bop-models)");
    DatabaseParams params;
    if (const auto cam = b->camera.camera()) {
      params.camera = cam->K;
      if (params.camera.width == 0) {
        params.camera.width = 640;
        params.camera.height = 480;
      }
    }
    params.subdivisions = b->views == 20 ? 0 : b->views == 80 ? 1 : 2;
    params.distance_m = b->distance;
    params.describe.vfh.pcl_compatible = !b->corrected_vfh;
    ViewDatabase db;
    {
      ProgressBar bar("db build", models.size());
      db = build_view_database(models, params, [&](std::size_t done, std::size_t) { bar.update(done); });
    }
    db.save(b->out);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print("built in {:.2f} s ({:.2f} s per object)\n", seconds, seconds / static_cast<double>(models.size()));
    print_database(b->out, db);
    exit_code = 0;
  });

  struct AddViewOptions {
    std::string cloud, object, db;
  };
  auto a = std::make_shared<AddViewOptions>();
  CLI::App* add_view = db_cmd->add_subcommand("add-view", "Add a view scanned with a real sensor (PCD/PLY of the object alone)");
  add_view->add_option("cloud", a->cloud, "The object's points, in the capturing camera's frame")->required()->check(CLI::ExistingFile);
  add_view->add_option("--object", a->object, "Object name: a new scanned object, or one to give another view")->required();
  add_view->add_option("--db", a->db, "Database to add to (made, with default parameters, if missing)")->required();
  add_view->callback([a, &exit_code] {
    ViewDatabase db;
    if (fs::exists(a->db)) db = ViewDatabase::load(a->db);
    const std::string ext = fs::path(a->cloud).extension().string();
    const PointCloud cloud = ext == ".ply" ? read_ply(a->cloud).cloud : read_pcd(a->cloud).cloud;
    const int id = add_captured_view(db, cloud, a->object);
    db.save(a->db);
    fmt::print("added a view of '{}' (id {}) from {}\n", a->object, id, a->cloud);
    print_database(a->db, db);
    exit_code = 0;
  });

  auto file = std::make_shared<std::string>();
  CLI::App* info = db_cmd->add_subcommand("info", "Objects, views, sizes and build parameters of a database");
  info->add_option("database", *file, "Database file")->required();
  info->callback([file, &exit_code] {
    print_database(*file, ViewDatabase::load(*file));
    exit_code = 0;
  });
}

}  // namespace viewpose::cli
