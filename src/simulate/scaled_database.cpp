#include "viewpose/simulate/scaled_database.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <fmt/format.h>

namespace viewpose {

ViewDatabase scaled_database(const ViewDatabase& db, std::size_t objects, std::uint64_t seed) {
  ViewDatabase out;
  out.params = db.params;
  if (db.objects.empty()) return out;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // The originals keep their ids (a dataset's ground truth names them); the copies take new ones
  // above them all.
  int largest_id = 0;
  for (const DatabaseObject& object : db.objects) largest_id = std::max(largest_id, object.id);
  for (std::size_t o = 0; o < objects; ++o) {
    const std::size_t source = o % db.objects.size();
    DatabaseObject object = db.objects[source];
    if (o >= db.objects.size()) {
      object.id = largest_id + static_cast<int>(o - db.objects.size() + 1);
      object.name = fmt::format("{}_{}", object.name, o / db.objects.size());
      object.nearest_cells = std::vector<std::uint32_t>();  // freed (not cleared): a database this large stores few
    }
    out.objects.push_back(std::move(object));
    for (const ViewEntry& v : db.views) {
      if (v.object != source) continue;
      ViewEntry copy;
      copy.object = static_cast<std::uint32_t>(o);
      copy.T_view_object = v.T_view_object;
      copy.vfh = v.vfh;
      if (o >= db.objects.size()) {
        // A smooth wave across the bins (another object's histograms differ in their broad shape,
        // not bin by bin only) times bin-by-bin noise.
        const double amplitude = 0.3 + 0.4 * unit(rng), period = 20 + 60 * unit(rng), phase = 2 * M_PI * unit(rng);
        for (std::size_t b = 0; b < copy.vfh.size(); ++b) {
          const double wave = 1 + amplitude * std::sin(2 * M_PI * static_cast<double>(b) / period + phase);
          copy.vfh[b] = static_cast<float>(copy.vfh[b] * wave * (0.85 + 0.3 * unit(rng)));
        }
      }
      copy.crh = v.crh;
      copy.centroid = v.centroid;
      out.views.push_back(std::move(copy));
    }
  }
  return out;
}

}  // namespace viewpose
