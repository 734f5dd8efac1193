#pragma once
// Objects named on the command line: built-in shapes (jug, box, can, mug) or mesh files, and the
// meshes of a BOP models/ folder. A mesh file keeps its own frame: poses are reported in it.
#include <filesystem>
#include <string>
#include <vector>

#include "viewpose/core/units.hpp"
#include "viewpose/database/view_database.hpp"

namespace viewpose::cli {

/// Ids 1, 2, ... in the order given.
std::vector<ObjectModel> load_models(const std::vector<std::string>& models, LengthUnit unit);

/// Every obj_NNNNNN.ply of a BOP models folder (millimetres), with N as its id.
std::vector<ObjectModel> load_bop_models(const std::filesystem::path& dir);

}  // namespace viewpose::cli
