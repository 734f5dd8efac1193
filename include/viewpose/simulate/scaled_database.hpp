#pragma once
// A large database made from a small one, to measure matching time and memory at the scale of a
// thousand objects without rendering a thousand meshes: each object is repeated with new ids, and
// each repeat's view histograms are perturbed bin by bin (x 0.7 to 1.3), so that no two views are
// the same and the repeats crowd around the originals (harder for an index than distinct
// objects). The views' point copies, which recognition does not read, are left out.
#include <cstdint>

#include "viewpose/database/view_database.hpp"

namespace viewpose {

ViewDatabase scaled_database(const ViewDatabase& db, std::size_t objects, std::uint64_t seed);

}  // namespace viewpose
