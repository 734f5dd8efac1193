#pragma once
// Results in the BOP19 CSV format: a header line, then one line per estimate
//   scene_id,im_id,obj_id,score,R,t,time
// with R the 9 entries of the rotation row-major and t the translation in mm (space-separated), and
// time the seconds spent on the whole image (the same on every line of an image; -1 when unknown).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "viewpose/core/transform.hpp"

namespace viewpose {

struct BopResult {
  int scene_id = 0;
  int im_id = 0;
  int obj_id = 0;
  double score = 0.0;
  Transform T_camera_object = Transform::Identity();  ///< metres
  double time_s = -1.0;
};

std::string format_bop_results(const std::vector<BopResult>& results);
/// Rotations are taken as rounded, as in the BOP json files (io/bop.hpp): the nearest rotation, with
/// one line in `notes` (when given) if any was off orthonormal by more than a last digit; a
/// reflection or a scaled or sheared matrix is an error naming the line.
std::vector<BopResult> parse_bop_results(std::string_view csv_text, std::string_view name,
                                         std::vector<std::string>* notes = nullptr);

void write_bop_results(const std::filesystem::path& path, const std::vector<BopResult>& results);  // atomic
std::vector<BopResult> read_bop_results(const std::filesystem::path& path, std::vector<std::string>* notes = nullptr);

}  // namespace viewpose
