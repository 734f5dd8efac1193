#include "viewpose/io/bop_results.hpp"

#include <cmath>

#include <fmt/format.h>

#include "text.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/core/file.hpp"

namespace viewpose {

namespace {
constexpr std::string_view kHeader = "scene_id,im_id,obj_id,score,R,t,time";
}

std::string format_bop_results(const std::vector<BopResult>& results) {
  std::string out(kHeader);
  out += '\n';
  for (const BopResult& r : results) {
    const Eigen::Matrix3d R = r.T_camera_object.linear();
    const Eigen::Vector3d t = r.T_camera_object.translation() * 1000.0;
    out += fmt::format("{},{},{},{},{} {} {} {} {} {} {} {} {},{} {} {},{}\n", r.scene_id, r.im_id, r.obj_id, r.score,
                       R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2), t.x(), t.y(),
                       t.z(), r.time_s);
  }
  return out;
}

std::vector<BopResult> parse_bop_results(std::string_view csv_text, std::string_view name, std::vector<std::string>* notes) {
  const std::span bytes(reinterpret_cast<const std::uint8_t*>(csv_text.data()), csv_text.size());
  text::LineReader lines(bytes);
  std::string_view line;
  if (!lines.next(line) || text::trim(line) != kHeader) {
    throw Error(fmt::format("{}: not a BOP results file (the first line must be '{}')", name, kHeader));
  }
  std::vector<BopResult> results;
  int adjusted = 0;
  double worst = 0;
  std::size_t worst_line = 0;
  for (std::size_t number = 2; lines.next(line); ++number) {
    if (text::trim(line).empty()) continue;
    const auto fail = [&](std::string_view why) -> void {
      throw Error(fmt::format("{}: line {}: {}", name, number, why));
    };
    const auto cols = text::split(line, ',');
    if (cols.size() != 7) fail(fmt::format("{} columns, expected 7", cols.size()));
    BopResult r;
    if (!text::parse_number(text::trim(cols[0]), r.scene_id) || !text::parse_number(text::trim(cols[1]), r.im_id) ||
        !text::parse_number(text::trim(cols[2]), r.obj_id)) {
      fail("scene_id, im_id and obj_id must be whole numbers");
    }
    if (!text::parse_number(text::trim(cols[3]), r.score) || !std::isfinite(r.score)) fail("score is not a number");
    if (!text::parse_number(text::trim(cols[6]), r.time_s) || !std::isfinite(r.time_s)) fail("time is not a number");
    const auto R_values = text::split_whitespace(cols[4]);
    const auto t_values = text::split_whitespace(cols[5]);
    if (R_values.size() != 9 || t_values.size() != 3) fail("R must be 9 numbers and t 3, separated by spaces");
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    for (int i = 0; i < 9; ++i) {
      if (!text::parse_number(R_values[static_cast<std::size_t>(i)], R(i / 3, i % 3))) fail("R holds a non-number");
    }
    for (int i = 0; i < 3; ++i) {
      if (!text::parse_number(t_values[static_cast<std::size_t>(i)], t[i])) fail("t holds a non-number");
    }
    const NearRotation near = nearest_rotation(R);
    if (near.kind == NearRotation::Kind::Reflection) {
      fail(fmt::format("R is a reflection (determinant {:.3g}), not a rotation", R.determinant()));
    }
    if (near.kind == NearRotation::Kind::NotRigid) {
      const Eigen::Vector3d& s = near.singular_values;
      fail(fmt::format("R is not a rotation matrix: it is scaled or sheared (singular values {:.4g}, {:.4g}, {:.4g}; "
                       "rounding explains at most {:g} from 1)", s[0], s[1], s[2], kMaxRotationRounding));
    }
    if (near.deviation > kSilentRotationRounding) {
      ++adjusted;
      if (near.deviation > worst) {
        worst = near.deviation;
        worst_line = number;
      }
    }
    if (!t.allFinite()) fail("t is not finite");
    r.T_camera_object = make_transform(near.R, t / 1000.0);
    results.push_back(r);
  }
  if (notes && adjusted > 0) {
    notes->push_back(fmt::format("{}: {} rotation{} off orthonormal by up to {:.1e} (line {} the most), taken as the "
                                 "nearest rotation{}", name, adjusted, adjusted == 1 ? " is" : "s are", worst, worst_line,
                                 adjusted == 1 ? "" : "s"));
  }
  return results;
}

void write_bop_results(const std::filesystem::path& path, const std::vector<BopResult>& results) {
  write_file_atomic(path, format_bop_results(results));
}

std::vector<BopResult> read_bop_results(const std::filesystem::path& path, std::vector<std::string>* notes) {
  const auto bytes = read_file_bytes(path);
  return parse_bop_results(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path.string(),
                           notes);
}

}  // namespace viewpose
