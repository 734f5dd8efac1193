// `viewpose info FILE...`: what each file holds, or one line saying why it cannot be used.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "camera_flags.hpp"
#include "commands.hpp"
#include "viewpose/core/error.hpp"

namespace viewpose::cli {

namespace fs = std::filesystem;

void print_file_info(const fs::path& path, const FileInfo& info) {
  fmt::print("{}\n  kind:         {}\n", path.string(), info.kind);
  if (info.faces > 0) {
    fmt::print("  vertices:     {}\n  faces:        {}\n", info.points, info.faces);
  } else if (info.points > 0 || !info.fields.empty()) {
    const std::string layout = info.height > 1 ? fmt::format("organized {} x {}", info.width, info.height)
                                               : std::string("unorganized");
    if (info.kind.find("PNG") != std::string::npos) {
      fmt::print("  pixels:       {} x {}, {} with depth\n", info.width, info.height, info.valid_points);
    } else {
      fmt::print("  points:       {} ({} valid), {}\n", info.points, info.valid_points, layout);
    }
  }
  if (!info.fields.empty()) fmt::print("  fields:       {}\n", fmt::join(info.fields, " "));
  if (!info.bbox.empty) {
    const auto& b = info.bbox;
    const Eigen::Vector3f s = b.size();
    const std::string unit = info.bbox_unit ? std::string(to_string(*info.bbox_unit)) : std::string("file units");
    fmt::print("  bounding box: [{:.4g}, {:.4g}, {:.4g}] to [{:.4g}, {:.4g}, {:.4g}] {} (size {:.4g} x {:.4g} x {:.4g})\n",
               b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z(), unit, s.x(), s.y(), s.z());
  }
  if (info.unit_guess) {
    fmt::print("  units guess:  {} ({})\n", unit_name(info.unit_guess->unit),
               info.unit_guess->reason);
  }
  for (const auto& note : info.notes) fmt::print("  {}\n", note);
}

void add_info_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::vector<std::string> files;
    CameraFlags camera;
  };
  auto opts = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "info", "Say what files hold: PCD, PLY, meshes (OBJ, STL, OFF, ...), 16-bit depth PNG, BOP json, BOP results "
              "CSV, BOP dataset folders");
  cmd->add_option("files", opts->files, "Files or BOP dataset folders")->required();
  opts->camera.add_to(*cmd);
  cmd->footer("With --camera or --intrinsics, depth PNGs are also turned into points and their box reported.");
  cmd->callback([opts, &exit_code] {
    InspectOptions options;
    options.depth_png_metres_per_unit = opts->camera.depth_scale() / 1000.0;
    if (const auto cam = opts->camera.camera()) options.camera = cam->K;
    bool first = true;
    for (const std::string& file : opts->files) {
      try {
        const FileInfo info = inspect_file(file, options);
        if (!first) fmt::print("\n");
        first = false;
        print_file_info(file, info);
        for (const auto& problem : info.problems) {
          fmt::print(stderr, "viewpose: error: {}: {}\n", file, problem);
          exit_code = 1;
        }
      } catch (const Error& e) {
        std::fflush(stdout);
        fmt::print(stderr, "viewpose: error: {}\n", e.what());
        exit_code = 1;
      }
    }
  });
}

}  // namespace viewpose::cli
