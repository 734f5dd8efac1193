#pragma once
// Objects named on the command line (io/object_models.hpp), their warnings logged.
#include <filesystem>
#include <string>
#include <vector>

#include "viewpose/core/units.hpp"
#include "viewpose/database/view_database.hpp"
#include "viewpose/io/object_models.hpp"  // load_bop_models

namespace viewpose::cli {

/// Ids 1, 2, ... in the order given.
std::vector<ObjectModel> load_models(const std::vector<std::string>& models, LengthUnit unit);

}  // namespace viewpose::cli
