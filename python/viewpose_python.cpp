// `import viewpose`: databases, recognition and depth PNGs for Python. Depth comes in as a numpy
// array (uint16 in the camera's units with a depth scale, or float metres), poses go out as 4x4
// float64 arrays in metres. A frame gives exactly what `viewpose recognize` gives on it: the same
// library calls in the same order. viewpose::Error becomes viewpose.Error with the same message.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <fmt/format.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "viewpose/core/error.hpp"
#include "viewpose/core/units.hpp"
#include "viewpose/database/view_database.hpp"
#include "viewpose/io/depth_png.hpp"
#include "viewpose/io/object_models.hpp"
#include "viewpose/io/recognition_json.hpp"
#include "viewpose/recognize/frame.hpp"
#include "viewpose/recognize/recognizer.hpp"

namespace py = pybind11;
using namespace viewpose;

namespace {

void warn(const std::string& message) {
  if (PyErr_WarnEx(PyExc_UserWarning, message.c_str(), 1) != 0) throw py::error_already_set();
}

py::array_t<double> pose_array(const Transform& T) {
  py::array_t<double> out({4, 4});
  auto m = out.mutable_unchecked<2>();
  const Eigen::Matrix4d M = T.matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = M(r, c);
  return out;
}

// The numpy depth as a frame: uint16 units times depth_scale millimetres (as a depth PNG is read), or
// float metres (0 or NaN: no measurement).
Frame frame_from_array(const py::array& depth, const std::tuple<double, double, double, double>& K,
                       std::optional<double> depth_scale_mm) {
  if (depth.ndim() != 2) throw Error(fmt::format("depth: a 2-D array (height x width) is needed, not {}-D", depth.ndim()));
  const int height = static_cast<int>(depth.shape(0)), width = static_cast<int>(depth.shape(1));
  CameraIntrinsics intrinsics{std::get<0>(K), std::get<1>(K), std::get<2>(K), std::get<3>(K), width, height};
  if (!(intrinsics.fx > 0 && intrinsics.fy > 0)) throw Error("K: the focal lengths (fx, fy) must be positive pixels");
  DepthImage image;
  if (py::isinstance<py::array_t<std::uint16_t>>(depth)) {
    const double scale = depth_scale_mm.value_or(1.0);
    const auto units = py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>::ensure(depth);
    image = depth_from_units({units.data(), static_cast<std::size_t>(units.size())}, width, height, scale / 1000.0);
    if (std::string w = depth_scale_warning(image, scale); !w.empty()) {
      // The command's message names its flag; here the same number is a keyword argument.
      if (const auto at = w.find("--depth-scale "); at != std::string::npos) w.replace(at, 14, "depth_scale=");
      warn("depth: " + w);
    }
  } else if (py::isinstance<py::array_t<float>>(depth) || py::isinstance<py::array_t<double>>(depth)) {
    if (depth_scale_mm) throw Error("depth: a float array is in metres; depth_scale is for integer units (uint16)");
    const auto metres = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(depth);
    image = DepthImage(width, height);
    const float* z = metres.data();
    for (std::size_t i = 0; i < image.depth_m.size(); ++i) {
      if (std::isfinite(z[i]) && z[i] > 0) image.depth_m[i] = z[i];
    }
    const double median = median_depth_m(image);
    if (std::isfinite(median) && !within_depth_camera_range(median)) {
      warn(fmt::format("depth: median {:.3g} m, outside what depth cameras measure (0.3-5 m): float depth is read in metres",
                       median));
    }
  } else {
    throw Error(fmt::format("depth: uint16 (with depth_scale) or float32 metres are read, not {}",
                            std::string(py::str(depth.dtype()))));
  }
  return frame_from_depth(std::move(image), intrinsics);
}

}  // namespace

PYBIND11_MODULE(viewpose, m) {
  m.doc() = "Known objects and their 6-DoF poses in one depth frame, from CAD models (viewpose).";
  m.attr("__version__") = VIEWPOSE_VERSION;
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      error(e.what());
    }
  });

  py::class_<DatabaseObject>(m, "DatabaseObject", "An object of a view database")
      .def_readonly("id", &DatabaseObject::id)
      .def_readonly("name", &DatabaseObject::name)
      .def_readonly("diameter_m", &DatabaseObject::diameter_m)
      .def("__repr__", [](const DatabaseObject& o) {
        return fmt::format("DatabaseObject(id={}, name='{}', diameter_m={:.4f})", o.id, o.name, o.diameter_m);
      });

  py::class_<ViewDatabase, std::shared_ptr<ViewDatabase>>(m, "ViewDatabase",
                                                          "Every object rendered from a view sphere and described")
      .def_static(
          "load",
          [](const std::filesystem::path& path, bool pair_tables) {
            return std::make_shared<ViewDatabase>(ViewDatabase::load(path, {.pair_tables = pair_tables}));
          },
          py::arg("path"), py::kw_only(), py::arg("pair_tables") = true,
          "Reads a database `viewpose db build` (or save) wrote; pair_tables=False leaves its point pair tables "
          "unread, as `viewpose recognize` of one file does (a recognizer that votes reads them from the file when it "
          "first needs them, or makes them where the file has changed since)")
      .def("save", &ViewDatabase::save, py::arg("path"), "Writes the database (atomically)")
      .def_readonly("objects", &ViewDatabase::objects)
      .def_property_readonly("view_count", [](const ViewDatabase& db) { return db.views.size(); })
      .def("__repr__", [](const ViewDatabase& db) {
        return fmt::format("ViewDatabase({} objects, {} views)", db.objects.size(), db.views.size());
      });

  m.def(
      "build_database",
      [](const std::vector<std::string>& models, const std::string& unit, int subdivisions, double distance_m) {
        LoadedObjectModels loaded = load_object_models(models, parse_length_unit(unit));
        for (const std::string& w : loaded.warnings) warn(w);
        DatabaseParams params;
        params.subdivisions = subdivisions;
        params.distance_m = distance_m;
        py::gil_scoped_release unlocked;
        return std::make_shared<ViewDatabase>(build_view_database(loaded.objects, params));
      },
      py::arg("models"), py::kw_only(), py::arg("unit") = "m", py::arg("subdivisions") = 1, py::arg("distance_m") = 1.0,
      "A database of mesh files (or built-in shapes: jug, box, can, mug), as `viewpose db build` makes it. "
      "unit: the meshes' length unit, m, cm or mm.");

  m.def(
      "read_depth_png",
      [](const std::filesystem::path& path) {
        DepthPngUnits png = read_depth_png_units(path);
        py::array_t<std::uint16_t> out({png.height, png.width});
        std::copy(png.units.begin(), png.units.end(), out.mutable_data());
        return out;
      },
      py::arg("path"), "A 16-bit depth PNG's values as they are stored (height x width uint16; 0 = no measurement)");

  py::class_<Detection>(m, "Detection", "A recognized object and its pose")
      .def_readonly("object_id", &Detection::object_id)
      .def_readonly("object_name", &Detection::object_name)
      .def_readonly("score", &Detection::score, "Estimated probability that the pose is right")
      .def_property_readonly("T_camera_object", [](const Detection& d) { return pose_array(d.T_camera_object); },
                             "4x4 float64, metres: a point in the object's frame to the camera's")
      .def_readonly("icp_fitness", &Detection::icp_fitness)
      .def_readonly("icp_rmse_m", &Detection::icp_rmse_m)
      .def_readonly("match_rank", &Detection::match_rank)
      .def_readonly("cluster_points", &Detection::cluster_points)
      .def_readonly("from_split_cluster", &Detection::from_split_cluster)
      .def_readonly("runner_up_score", &Detection::runner_up_score)
      .def_property_readonly("fit_score", [](const Detection& d) { return d.verification.score; })
      .def("__repr__", [](const Detection& d) {
        const Eigen::Vector3d t = d.T_camera_object.translation();
        return fmt::format("Detection({} '{}', score={:.3f}, t_m=({:.4f}, {:.4f}, {:.4f}))", d.object_id, d.object_name,
                           d.score, t.x(), t.y(), t.z());
      });

  py::class_<Recognition>(m, "Recognition", "What one frame gave: its detections (iterable) and how long each stage took")
      .def_readonly("detections", &Recognition::detections)
      .def_readonly("cut_short", &Recognition::cut_short)
      .def_readonly("clusters", &Recognition::clusters)
      .def_readonly("hypotheses", &Recognition::hypotheses)
      .def_readonly("repeats", &Recognition::repeats)
      .def_readonly("screened", &Recognition::screened)
      .def_readonly("screened_out", &Recognition::screened_out)
      .def_readonly("screened_merged", &Recognition::screened_merged,
                    "Screened poses led where another of their region's was led and refined, not refined again")
      .def_readonly("icp_steps", &Recognition::icp_steps, "ICP steps of the poses refined in full (the screen's not counted)")
      .def_readonly("regions", &Recognition::regions)
      .def_readonly("parts_unreached", &Recognition::parts_unreached,
                    "Convex parts of split clusters the search never reached (a pose found, the budget spent or the deadline passed first): not described")
      .def_readonly("split_clusters", &Recognition::split_clusters, "Clusters whose search went on in their convex parts")
      .def_readonly("joined_regions", &Recognition::joined_regions, "Pairs of unexplained pieces searched as one region")
      .def_readonly("grown_regions", &Recognition::grown_regions,
                    "Regions grown from a part's pose into the rest of its cluster and searched again")
      .def_readonly("voted_regions", &Recognition::voted_regions,
                    "Regions in which point pair votes were cast (each object's votes once per region)")
      .def_readonly("best_below_min_score", &Recognition::best_below_min_score,
                    "The most confident pose that passed verification but scored below min_score (a Detection, or None): "
                    "how near an object not reported came")
      .def_readonly("dropped_as_explained", &Recognition::dropped_as_explained,
                    "Detections dropped because a more confident one explains the same pixels")
      .def_readonly("dropped_inside_planes", &Recognition::dropped_inside_planes,
                    "Poses refused, or detections dropped, because their model would lie inside a removed plane (a table)")
      .def_readonly("lifted_out_of_planes", &Recognition::lifted_out_of_planes,
                    "Poses sunk a little into a removed plane, lifted onto it and kept there (they passed again)")
      .def_property_readonly("times_ms",
                             [](const Recognition& r) {
                               const StageTimes& t = r.times;
                               py::dict d;
                               d["downsample"] = t.downsample_ms, d["segment"] = t.segment_ms, d["normals"] = t.normals_ms;
                               d["vfh"] = t.vfh_ms, d["match"] = t.match_ms, d["crh"] = t.crh_ms, d["icp"] = t.icp_ms;
                               d["verify"] = t.verify_ms, d["split"] = t.split_ms, d["total"] = t.total_ms;
                               return d;
                             })
      .def("to_json", [](const Recognition& r, bool with_times) { return recognition_json(r, with_times).dump(); },
           py::kw_only(), py::arg("with_times") = true, "The JSON text `viewpose recognize --json` writes (without its scene key)")
      .def("__len__", [](const Recognition& r) { return r.detections.size(); })
      .def("__getitem__",
           [](const Recognition& r, std::size_t i) {
             if (i >= r.detections.size()) throw py::index_error();
             return r.detections[i];
           })
      .def("__iter__", [](const Recognition& r) { return py::make_iterator(r.detections.begin(), r.detections.end()); },
           py::keep_alive<0, 1>());

  py::class_<Recognizer>(m, "Recognizer", "Recognizes the database's objects in depth frames")
      .def(py::init([](std::shared_ptr<ViewDatabase> db, bool keep_best, bool split_touching, std::size_t matches,
                       std::size_t budget, std::size_t screen, const std::string& source, double deadline_ms,
                       std::optional<double> min_score) {
             RecognizerOptions o;
             try {
               o.match.source = pose_source_from_name(source);
             } catch (const Error& e) {
               throw py::value_error(e.what());  // (a wrong argument value, as Python names it)
             }
             o.accept.keep_best = keep_best;
             o.split.enabled = split_touching;
             o.match.per_object = matches;
             o.match.max_hypotheses = budget;
             o.match.prescreen = screen;
             o.run.deadline_ms = deadline_ms;
             if (min_score) o.accept.min_confidence = *min_score;
             return std::make_unique<Recognizer>(std::shared_ptr<const ViewDatabase>(std::move(db)), o);
           }),
           py::arg("db"), py::kw_only(), py::arg("keep_best") = false, py::arg("split_touching") = true,
           py::arg("matches") = RecognizerOptions{}.match.per_object,
           py::arg("budget") = RecognizerOptions{}.match.max_hypotheses, py::arg("screen") = RecognizerOptions{}.match.prescreen,
           py::arg("source") = std::string(pose_source_name(RecognizerOptions{}.match.source)), py::arg("deadline_ms") = 0.0, py::arg("min_score") = py::none(),
           "Options as `viewpose recognize` has them: keep_best, split_touching (--no-split is False), matches, "
           "budget (0: every starting pose), screen (0: coarse fit order only), source (\"vfh\", \"ppf\", \"both\" or \"touching\": where "
           "starting poses come from, --source), deadline_ms (0: none), min_score "
           "(None: the default threshold)")
      .def(
          "recognize",
          [](const Recognizer& r, const py::array& depth, const std::tuple<double, double, double, double>& K,
             std::optional<double> depth_scale) {
            Frame frame = frame_from_array(depth, K, depth_scale);
            py::gil_scoped_release unlocked;
            return r.recognize(frame);
          },
          py::arg("depth"), py::kw_only(), py::arg("K"), py::arg("depth_scale") = py::none(),
          "depth: height x width uint16 in units of depth_scale millimetres (BOP's depth_scale; default 1), or "
          "float32 metres. K: (fx, fy, cx, cy) in pixels.");
}
