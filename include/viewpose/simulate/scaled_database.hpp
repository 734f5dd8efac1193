#pragma once
// A large database made from a small one, to measure matching time and memory at the scale of a
// thousand objects without rendering a thousand meshes: object k of the result is object k mod n of
// the n given (the first n are those, with their ids, which a dataset's ground truth names; the
// copies have new ids above all of theirs), and each copy's view histograms are reshaped by a
// smooth random wave across the bins (x 0.3 to 1.7, one per view) and bin-by-bin noise (x 0.85 to
// 1.15), so that no two views are the same while the copies stay near the originals. The views'
// point copies, which recognition does not read, are left out.
#include <cstdint>

#include "viewpose/database/view_database.hpp"

namespace viewpose {

ViewDatabase scaled_database(const ViewDatabase& db, std::size_t objects, std::uint64_t seed);

}  // namespace viewpose
