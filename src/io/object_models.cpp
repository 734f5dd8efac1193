#include "viewpose/io/object_models.hpp"

#include <algorithm>
#include <map>

#include <fmt/format.h>

#include "viewpose/core/error.hpp"
#include "viewpose/io/bop.hpp"
#include "viewpose/io/mesh_loader.hpp"
#include "viewpose/io/ply.hpp"
#include "viewpose/render/shapes.hpp"

namespace viewpose {

namespace fs = std::filesystem;

LoadedObjectModels load_object_models(std::span<const std::string> models, LengthUnit unit) {
  LoadedObjectModels out;
  const auto names = shape_names();
  for (const std::string& m : models) {
    ObjectModel o;
    o.id = static_cast<int>(out.objects.size()) + 1;
    if (std::find(names.begin(), names.end(), m) != names.end() && !fs::exists(m)) {
      o.name = m;
      o.mesh = make_named_shape(m);
    } else {
      LoadedMesh loaded = load_mesh(m, unit);
      for (auto& w : loaded.warnings) out.warnings.push_back(std::move(w));
      o.name = fs::path(m).stem().string();
      o.mesh = std::move(loaded.mesh);
    }
    out.objects.push_back(std::move(o));
  }
  return out;
}

std::vector<ObjectModel> load_bop_models(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw Error(fmt::format("{}: not a folder of BOP models", dir.string()));
  const std::map<int, fs::path> files = find_bop_model_files(dir);
  if (files.empty()) throw Error(fmt::format("{}: no obj_NNNNNN.ply models in it", dir.string()));
  std::vector<ObjectModel> out;
  for (const auto& [id, path] : files) {
    PlyFile ply = read_ply(path);
    if (!ply.has_faces()) throw Error(fmt::format("{}: a point cloud, not a mesh", path.string()));
    ObjectModel o{id, path.stem().string(), std::move(ply.mesh)};
    for (auto& v : o.mesh.vertices) v *= 0.001f;  // BOP models are in millimetres
    o.mesh.normals.clear();
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace viewpose
