#include "viewpose/core/units.hpp"

#include <fmt/format.h>

#include "viewpose/core/error.hpp"

namespace viewpose {

namespace {
// Diagonal, in file units, from which a box is read as millimetres: 10 m is past any depth
// camera's range and 10 mm is smaller than anything worth grasping.
constexpr float kMillimetreDiagonal = 10.0f;
}  // namespace

namespace {

// Each unit once: its size, its symbol and its name.
struct UnitRow {
  LengthUnit unit;
  double metres;
  std::string_view symbol, name;
};
constexpr UnitRow kUnits[] = {{LengthUnit::Metres, 1.0, "m", "metres"},
                              {LengthUnit::Millimetres, 0.001, "mm", "millimetres"},
                              {LengthUnit::Centimetres, 0.01, "cm", "centimetres"}};

const UnitRow& row(LengthUnit unit) {
  for (const UnitRow& r : kUnits)
    if (r.unit == unit) return r;
  return kUnits[0];
}

}  // namespace

double metres_per_unit(LengthUnit unit) { return row(unit).metres; }

std::string_view to_string(LengthUnit unit) { return row(unit).symbol; }

std::string_view unit_name(LengthUnit unit) { return row(unit).name; }

LengthUnit parse_length_unit(std::string_view text) {
  if (text == "m" || text == "metres" || text == "meters") return LengthUnit::Metres;
  if (text == "mm" || text == "millimetres" || text == "millimeters") return LengthUnit::Millimetres;
  if (text == "cm" || text == "centimetres" || text == "centimeters") return LengthUnit::Centimetres;
  throw Error(fmt::format("unknown length unit '{}' (use m, mm or cm)", text));
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
  if (box.empty) return {};
  const double d = box.diagonal();
  const double across_m = d * metres_per_unit(declared);
  if (across_m <= 10.0 && across_m >= 0.01) return {};
  // The units in which this many file units make an object a hand or a robot deals with.
  std::string likely;
  for (const LengthUnit u : {LengthUnit::Millimetres, LengthUnit::Centimetres, LengthUnit::Metres}) {
    const double m = d * metres_per_unit(u);
    if (u == declared || m < 0.01 || m > 1.5) continue;
    likely += fmt::format("{}{} (--unit {})", likely.empty() ? "" : " or ", unit_name(u), to_string(u));
  }
  const std::string_view as = unit_name(declared);
  std::string w = across_m > 10.0 ? fmt::format("read as {} the model is {:.4g} m across", as, across_m)
                                   : fmt::format("read as {} the model is {:.3g} mm across", as, across_m * 1000.0);
  if (!likely.empty()) w += fmt::format("; it looks like {}", likely);
  return w;
}

}  // namespace viewpose
