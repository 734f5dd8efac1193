#include "viewpose/simulate/scaled_database.hpp"

#include <random>

#include <fmt/format.h>

namespace viewpose {

ViewDatabase scaled_database(const ViewDatabase& db, std::size_t objects, std::uint64_t seed) {
  ViewDatabase out;
  out.params = db.params;
  if (db.objects.empty()) return out;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> factor(0.7f, 1.3f);
  for (std::size_t o = 0; o < objects; ++o) {
    const std::size_t source = o % db.objects.size();
    DatabaseObject object = db.objects[source];
    object.id = static_cast<int>(o + 1);
    if (o >= db.objects.size()) object.name = fmt::format("{}_{}", object.name, o / db.objects.size());
    out.objects.push_back(std::move(object));
    for (const ViewEntry& v : db.views) {
      if (v.object != source) continue;
      ViewEntry copy;
      copy.object = static_cast<std::uint32_t>(o);
      copy.T_view_object = v.T_view_object;
      copy.vfh = v.vfh;
      if (o >= db.objects.size()) {
        for (float& bin : copy.vfh) bin *= factor(rng);
      }
      copy.crh = v.crh;
      copy.centroid = v.centroid;
      out.views.push_back(std::move(copy));
    }
  }
  return out;
}

}  // namespace viewpose
