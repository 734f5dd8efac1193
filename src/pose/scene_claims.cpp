#include "viewpose/pose/scene_claims.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "viewpose/render/rasterizer.hpp"

namespace viewpose {

std::vector<std::uint32_t> claimed_pixels(const VerifyModel& model, const Transform& T_camera_object,
                                          const DepthImage& observed, const CameraIntrinsics& K,
                                          const VerifyOptions& verify) {
  std::vector<std::uint32_t> claimed;
  if (observed.width != K.width || observed.height != K.height) return claimed;
  RenderedFrame drawn;
  if (model.mesh && !model.mesh->triangles.empty()) {
    const MeshInstance instance{model.mesh, T_camera_object};
    RenderOptions ro;
    ro.instances = false;
    ro.closed_winding = model.closed_winding;
    drawn = render(std::span<const MeshInstance>(&instance, 1), K, ro);
  } else {
    drawn = render_points(model.points, T_camera_object, K, model.point_spacing_m);
  }
  const std::size_t n = observed.depth_m.size();
  for (std::size_t i = 0; i < n; ++i) {
    const float zm = drawn.depth.depth_m[i], zo = observed.depth_m[i];
    if (!std::isfinite(zm) || !std::isfinite(zo) || !(zo > 0)) continue;
    if (std::abs(zm - zo) <= depth_tolerance(zo, verify)) claimed.push_back(static_cast<std::uint32_t>(i));
  }
  return claimed;
}

std::vector<ClaimVerdict> resolve_claims(std::span<const std::vector<std::uint32_t>> claims,
                                         const SceneClaimOptions& options) {
  std::vector<ClaimVerdict> verdicts(claims.size());
  std::vector<std::uint32_t> owned;  // the kept poses' pixels, ascending
  for (std::size_t k = 0; k < claims.size(); ++k) {
    const std::vector<std::uint32_t>& c = claims[k];
    ClaimVerdict& v = verdicts[k];
    v.claimed = c.size();
    // Both ascending: one merge-like pass counts the pixels already owned.
    auto o = owned.begin();
    for (const std::uint32_t p : c) {
      o = std::lower_bound(o, owned.end(), p);
      if (o == owned.end()) break;
      if (*o == p) ++v.shared;
    }
    const std::size_t own = v.claimed - v.shared;
    v.kept = own >= options.min_own_pixels &&
             static_cast<double>(v.shared) <= options.max_shared_fraction * static_cast<double>(v.claimed);
    if (!v.kept) continue;
    std::vector<std::uint32_t> merged;
    merged.reserve(owned.size() + c.size());
    std::set_union(owned.begin(), owned.end(), c.begin(), c.end(), std::back_inserter(merged));
    owned.swap(merged);
  }
  return verdicts;
}

}  // namespace viewpose
