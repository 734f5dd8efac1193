#pragma once
// A large database made from a small one, to measure matching time and memory at the scale of a
// thousand objects without rendering a thousand meshes: each object is repeated with new ids, and
// each repeat's view histograms are reshaped by a smooth random wave across the bins (x 0.3 to 1.7,
// one per view) and bin-by-bin noise (x 0.85 to 1.15), so that no two views are the same while the
// repeats stay near the originals. The views' point copies, which recognition does not read, are
// left out.
#include <cstdint>

#include "viewpose/database/view_database.hpp"

namespace viewpose {

ViewDatabase scaled_database(const ViewDatabase& db, std::size_t objects, std::uint64_t seed);

}  // namespace viewpose
