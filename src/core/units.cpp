#include "viewpose/core/units.hpp"

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

namespace {
// Diagonal, in file units, from which a box is read as millimetres: 10 m is past any depth
// camera's range and 10 mm is smaller than anything worth grasping.
constexpr float kMillimetreDiagonal = 10.0f;
}  // namespace

double metres_per_unit(LengthUnit unit) { return unit == LengthUnit::Metres ? 1.0 : 0.001; }

std::string_view to_string(LengthUnit unit) { return unit == LengthUnit::Metres ? "m" : "mm"; }

LengthUnit parse_length_unit(std::string_view text) {
  if (text == "m" || text == "metres" || text == "meters") return LengthUnit::Metres;
  if (text == "mm" || text == "millimetres" || text == "millimeters") return LengthUnit::Millimetres;
  throw Error(fmt::format("unknown length unit '{}' (use m or mm)", text));
}

UnitGuess guess_length_unit(const BoundingBox& box) {
  if (box.empty) return {LengthUnit::Metres, "no finite coordinates to judge by"};
  const float d = box.diagonal();
  if (d >= kMillimetreDiagonal) {
    return {LengthUnit::Millimetres,
            fmt::format("diagonal {:.4g} would be {:.4g} m in metres, too large for an object or a depth frame", d, d)};
  }
  return {LengthUnit::Metres, fmt::format("diagonal {:.4g} fits metres ({:.4g} mm)", d, d * 1000.0f)};
}

std::string unit_mismatch_warning(const BoundingBox& box, LengthUnit declared) {
  const UnitGuess guess = guess_length_unit(box);
  if (box.empty || guess.unit == declared) return {};
  const float d = box.diagonal();
  return declared == LengthUnit::Metres
             ? fmt::format("read as metres the model spans {:.4g} m; it looks like millimetres (use unit mm)", d)
             : fmt::format("read as millimetres the model spans {:.4g} mm; it looks like metres (use unit m)", d);
}

}  // namespace viewpose
