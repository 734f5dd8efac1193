#pragma once
// The objects to recognize, from files: mesh files (any format assimp reads) or built-in shapes
// (jug, box, can, mug) named on a command line, and the meshes of a BOP models/ folder. A mesh file
// keeps its own frame: poses are reported in it.
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "viewpose/core/object_model.hpp"
#include "viewpose/core/units.hpp"

namespace viewpose {

struct LoadedObjectModels {
  std::vector<ObjectModel> objects;
  std::vector<std::string> warnings;  ///< e.g. a mesh whose size looks like another unit
};

/// Each of `models` is a mesh file in `unit`, or a built-in shape's name where no such file exists.
/// Ids 1, 2, ... in the order given; names are the files' stems. Throws viewpose::Error naming the
/// file that is missing or holds no mesh.
LoadedObjectModels load_object_models(std::span<const std::string> models, LengthUnit unit);

/// Every obj_NNNNNN.ply of a BOP models folder (millimetres), with N as its id, in id order.
std::vector<ObjectModel> load_bop_models(const std::filesystem::path& dir);

}  // namespace viewpose
