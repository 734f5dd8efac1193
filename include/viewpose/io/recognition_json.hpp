#pragma once
// A frame's recognition as JSON, as `viewpose recognize --json` writes it (and `bop --details` and
// `live --json-lines` a line per frame): each detection's object, pose (R row-major, t_m in metres),
// score and verification evidence; the frame's counts; `best_below_min_score`, where a pose met
// every bound of verification but not the confidence bound, the most confident such, in a
// detection's form (Recognition::best_below_min_score: beside detections it may be one of theirs
// at a rival pose); with `with_times`, each stage's time in ms.
// Callers add keys of their own (the scene's name, the frame's index) before writing it.
#include <nlohmann/json.hpp>

#include "viewpose/recognize/recognizer.hpp"

namespace viewpose {

nlohmann::json recognition_json(const Recognition& r, bool with_times = true);

/// One detection as recognition_json lists it.
nlohmann::json detection_json(const Detection& d);

/// One pose's verification evidence (a detection's "verification" above, and each line of `bop --hypotheses`).
nlohmann::json verification_json(const Verification& v);

}  // namespace viewpose
