#include <cstring>
#include <random>
#include <set>

#include "test_support.hpp"
#include "viewpose/core/error.hpp"
#include "viewpose/database/matching.hpp"
#include "viewpose/database/view_database.hpp"
#include "viewpose/core/file.hpp"
#include "viewpose/core/kdtree.hpp"
#include "viewpose/core/nearest_grid.hpp"
#include "viewpose/render/rasterizer.hpp"
#include "viewpose/render/simplify.hpp"
#include "viewpose/render/view_sphere.hpp"
#include "viewpose/render/shapes.hpp"
#include "viewpose/simulate/scaled_database.hpp"

namespace viewpose {
namespace {

using test::expect_error;

// Built once: the jug and a can from a 20-view sphere (fast enough for the sanitizer build).
const ViewDatabase& small_db() {
  static const ViewDatabase db = [] {
    const std::vector<ObjectModel> models = {{1, "jug", make_jug()}, {5, "can", make_can()}};
    DatabaseParams p;
    p.subdivisions = 0;
    return build_view_database(models, p);
  }();
  return db;
}

TEST(ViewDatabaseTest, HoldsEveryViewOfEveryObjectWithItsPose) {
  const ViewDatabase& db = small_db();
  ASSERT_EQ(db.objects.size(), 2u);
  EXPECT_EQ(db.objects[1].id, 5);
  EXPECT_NEAR(db.objects[0].diameter_m, mesh_diameter(make_jug()), 1e-9);
  ASSERT_EQ(db.views.size(), 40u);
  for (const ViewEntry& v : db.views) {
    EXPECT_GT(v.described_points, 300u);
    EXPECT_LT(v.icp_points.size(), v.described_points);  // the 5 mm copy is coarser
    EXPECT_NEAR(v.T_view_object.translation().norm(), 1.0, 0.02);  // 1 m from the object's centre
    float sum = 0;
    for (float b : v.vfh) sum += b;
    EXPECT_NEAR(sum, 400.0f, 2.0f);  // three angle histograms of ~100 and the viewpoint part's 100
  }
}

TEST(ViewDatabaseTest, ARenderedViewDescribesToItsEntryAndMatchesItselfFirst) {
  // The same describe code for views and scenes: re-rendering a view at its stored pose and
  // describing it gives the stored VFH, and the view is its own nearest match.
  const ViewDatabase& db = small_db();
  const std::vector<ObjectModel> models = {{1, "jug", make_jug()}, {5, "can", make_can()}};
  for (std::size_t i = 0; i < db.views.size(); i += 3) {
    const ViewEntry& stored = db.views[i];
    const MeshInstance inst{&models[stored.object].mesh, stored.T_view_object};
    const RenderedFrame frame = render(std::span(&inst, 1), db.params.camera);
    const ViewEntry again = describe_view(frame.depth, stored.T_view_object, stored.object, db.params);
    EXPECT_EQ(std::memcmp(again.vfh.data(), stored.vfh.data(), sizeof(Vfh)), 0) << "view " << i;
    const auto matches = nearest_views(db, again.vfh, 5);
    ASSERT_EQ(matches.size(), 5u);
    EXPECT_EQ(matches[0].distance, 0.0f);
    if (models[stored.object].name == "jug") {
      EXPECT_EQ(matches[0].view, i);  // no other view of the jug looks the same
    } else {
      // A can looks the same from several azimuths: an equivalent view may tie with it.
      EXPECT_EQ(db.views[matches[0].view].object, stored.object);
    }
    EXPECT_LE(matches[0].distance, matches[1].distance);
  }
}

TEST(ViewDatabaseTest, AnObjectTheViewCameraCannotSeeWholeOrHardlySeesIsRefusedWithItsUnit) {
  // A jug read in millimetres as metres is hundreds of metres across; a box in metres read as
  // millimetres is a tenth of a millimetre. Neither gives a usable view: refused before any work.
  TriangleMesh huge = make_jug();
  for (auto& v : huge.vertices) v *= 1000.0f;
  const ObjectModel big{1, "huge", huge};
  test::expect_error([&] { build_view_database(std::span(&big, 1), DatabaseParams{}); }, "--unit mm or --unit cm");
  const ObjectModel tiny{2, "tiny", make_box_mesh({0.0001f, 0.00006f, 0.0002f})};
  test::expect_error([&] { build_view_database(std::span(&tiny, 1), DatabaseParams{}); }, "--unit m");
  // Farther away, the camera sees a larger object whole.
  TriangleMesh wide = make_jug();
  for (auto& v : wide.vertices) v *= 4.0f;  // 1.4 m across
  const ObjectModel large{3, "large", wide};
  DatabaseParams far;
  far.subdivisions = 0;
  test::expect_error([&] { build_view_database(std::span(&large, 1), far); }, "larger --distance");
  far.distance_m = 3.0;
  EXPECT_EQ(build_view_database(std::span(&large, 1), far).views.size(), 20u);
}

TEST(ViewDatabaseTest, SurvivesAWriteReadRoundTripBitForBit) {
  const ViewDatabase& db = small_db();
  test::TempDir dir;
  db.save(dir / "db.vpdb");
  const ViewDatabase back = ViewDatabase::load(dir / "db.vpdb");
  EXPECT_EQ(back.serialize(), db.serialize());
  ASSERT_EQ(back.views.size(), db.views.size());
  EXPECT_TRUE(back.views[7].T_view_object.isApprox(db.views[7].T_view_object, 0.0));
  EXPECT_EQ(back.objects[1].name, "can");
  // The can's symmetries (a free turn about its axis, upside down) are stored; the jug has none.
  EXPECT_TRUE(back.objects[0].symmetries.empty());
  ASSERT_EQ(back.objects[1].symmetries.continuous.size(), 1u);
  ASSERT_EQ(back.objects[1].symmetries.discrete.size(), 1u);
  EXPECT_TRUE(back.objects[1].symmetries.discrete[0].isApprox(db.objects[1].symmetries.discrete[0], 0.0));
  EXPECT_EQ(back.params.subdivisions, 0);
  EXPECT_EQ(back.params.describe.vfh.pcl_compatible, db.params.describe.vfh.pcl_compatible);
  // What recognition would prepare is stored: a drawing mesh far smaller than the mesh, and a
  // filled nearest-point grid, as the recognizer would make them.
  for (std::size_t o = 0; o < db.objects.size(); ++o) {
    const DatabaseObject& object = back.objects[o];
    EXPECT_GT(object.drawn_mesh.triangles.size(), 8u);
    EXPECT_LT(object.drawn_mesh.triangles.size(), object.mesh.triangles.size() / 2);
    const TriangleMesh drawn = simplify_for_drawing(object.mesh, db.params.drawn_mesh_error_m);
    EXPECT_EQ(object.drawn_mesh.triangles, drawn.triangles);
    EXPECT_EQ(object.drawn_mesh.vertices, drawn.vertices);
    ASSERT_EQ(object.nearest_cells.size(), NearestGrid::cell_count(object.model_points, db.params.grid_cell_m, db.params.grid_margin_m));
    EXPECT_EQ(object.nearest_cells, filled_nearest_cells(object.model_points, db.params.grid_cell_m, db.params.grid_margin_m));
  }
}

TEST(ViewDatabaseTest, AScannedObjectsGridIsMadeAgainForItsGrownModel) {
  // Two captured views of the jug (rendered here as a sensor would see them): the model grows with
  // the second, and the stored grid must be the grown model's.
  const TriangleMesh jug = make_jug();
  const DatabaseParams params;
  ViewDatabase db;
  for (int k : {0, 7}) {
    const Transform pose = view_sphere_poses(Eigen::Vector3d::Zero(), params.distance_m, params.subdivisions)[static_cast<std::size_t>(k)];
    const MeshInstance inst{&jug, pose};
    const RenderedFrame frame = render(std::span(&inst, 1), params.camera);
    add_captured_view(db, depth_to_cloud(frame.depth, params.camera), "scanned jug");
  }
  ASSERT_EQ(db.objects.size(), 1u);
  ASSERT_EQ(db.views.size(), 2u);
  const DatabaseObject& o = db.objects[0];
  EXPECT_TRUE(o.drawn_mesh.triangles.empty()) << "a scan has no mesh to draw";
  EXPECT_EQ(o.nearest_cells, filled_nearest_cells(o.model_points, params.grid_cell_m, params.grid_margin_m));
}

TEST(ViewDatabaseTest, GridsAreStoredWithinTheirByteLimitAndDamagedOnesAreRefused) {
  const std::vector<ObjectModel> models = {{1, "jug", make_jug()}, {5, "can", make_can()}};
  DatabaseParams p;
  p.subdivisions = 0;
  // Room for the smaller grid alone: the larger is not stored, whichever comes first, and the
  // smaller is (an object that does not fit does not stop the next).
  const std::size_t jug = small_db().objects[0].nearest_cells.size(), can = small_db().objects[1].nearest_cells.size();
  ASSERT_NE(jug, can);
  p.max_grid_bytes = std::min(jug, can) * sizeof(std::uint32_t);
  const ViewDatabase db = build_view_database(models, p);
  const std::size_t larger = jug > can ? 0 : 1;
  EXPECT_TRUE(db.objects[larger].nearest_cells.empty()) << "over the limit: the recognizer fills it";
  EXPECT_FALSE(db.objects[1 - larger].nearest_cells.empty());
  EXPECT_FALSE(db.objects[larger].drawn_mesh.triangles.empty()) << "drawing meshes are small: always stored";
  EXPECT_EQ(stored_grid_bytes(db), std::min(jug, can) * sizeof(std::uint32_t));
  // The limit is kept in the file, for add-view.
  EXPECT_EQ(ViewDatabase::deserialize(db.serialize(), "limit.vpdb").params.max_grid_bytes, p.max_grid_bytes);
  // Parameters the file could not be read back with are refused before anything is rendered.
  DatabaseParams no_cells = p;
  no_cells.grid_cell_m = 0;
  expect_error([&] { build_view_database(models, no_cells); }, "grid_cell_m is 0");
  // A damaged grid (a cell past the model's points) is refused when the file is read.
  ViewDatabase bad = small_db();
  bad.objects[1].nearest_cells[5] = static_cast<std::uint32_t>(bad.objects[1].model_points.size() + 1);
  expect_error([&] { ViewDatabase::deserialize(bad.serialize(), "grid.vpdb"); }, "grid.vpdb: an object's nearest-point grid does not fit");
  bad.objects[1].nearest_cells.pop_back();
  expect_error([&] { ViewDatabase::deserialize(bad.serialize(), "grid.vpdb"); }, "does not fit its model points");
}

TEST(ViewDatabaseTest, PairTablesLeftOnDiskAreReadLaterAndOnlyFromTheFileLoaded) {
  const ViewDatabase& db = small_db();
  test::TempDir dir;
  db.save(dir / "tables.vpdb");
  const ViewDatabase without = ViewDatabase::load(dir / "tables.vpdb", {.pair_tables = false});
  ASSERT_TRUE(without.pair_tables_on_disk);
  EXPECT_FALSE(without.objects[0].pair_table || without.objects[1].pair_table);
  // Read later, they are the tables a whole load gives, object by object.
  const std::vector<std::shared_ptr<const PpfTable>> later = read_stored_pair_tables(without);
  ASSERT_EQ(later.size(), db.objects.size());
  for (std::size_t o = 0; o < later.size(); ++o) {
    ASSERT_TRUE(later[o]);
    EXPECT_EQ(later[o]->entries, db.objects[o].pair_table->entries);
    EXPECT_EQ(later[o]->key_start, db.objects[o].pair_table->key_start);
    EXPECT_EQ(later[o]->sampled.points, db.objects[o].pair_table->sampled.points);
  }
  // A whole load, or a file without tables, leaves nothing on disk to read.
  EXPECT_FALSE(ViewDatabase::load(dir / "tables.vpdb").pair_tables_on_disk);
  ViewDatabase bare = db;
  for (DatabaseObject& o : bare.objects) o.pair_table.reset();
  bare.save(dir / "bare.vpdb");
  EXPECT_FALSE(ViewDatabase::load(dir / "bare.vpdb", {.pair_tables = false}).pair_tables_on_disk);
  EXPECT_TRUE(read_stored_pair_tables(ViewDatabase::load(dir / "bare.vpdb", {.pair_tables = false})).empty());
  // Another database written over the file (a rebuild), the file damaged or gone: refused.
  ViewDatabase other = db;
  other.objects.pop_back();
  other.save(dir / "tables.vpdb");
  expect_error([&] { read_stored_pair_tables(without); }, "tables.vpdb: the file changed since it was loaded");
  db.save(dir / "tables.vpdb");
  EXPECT_EQ(read_stored_pair_tables(without).size(), db.objects.size());  // the same bytes again: the same file
  std::vector<std::uint8_t> file = db.serialize();
  file[file.size() - 100] ^= 0x10;
  write_file_atomic(dir / "tables.vpdb", file);
  expect_error([&] { read_stored_pair_tables(without); }, "checksum mismatch in the pair tables");
  std::filesystem::remove(dir / "tables.vpdb");
  expect_error([&] { read_stored_pair_tables(without); }, "no such file");
}

TEST(ViewDatabaseTest, PairTablesAreStoredWithinTheirByteLimitAndReadBackWhole) {
  const ViewDatabase& db = small_db();
  ASSERT_TRUE(db.objects[0].pair_table && db.objects[1].pair_table);
  const ViewDatabase back = ViewDatabase::deserialize(db.serialize(), "tables.vpdb");
  for (std::size_t o = 0; o < 2; ++o) {
    const PpfTable &a = *db.objects[o].pair_table, &b = *back.objects[o].pair_table;
    EXPECT_EQ(a.entries, b.entries);
    EXPECT_EQ(a.key_start, b.key_start);
    EXPECT_EQ(a.sampled.points, b.sampled.points);
    EXPECT_EQ(a.diameter_m, b.diameter_m);
    EXPECT_TRUE(b.made_with(db.params.ppf));
  }
  EXPECT_EQ(stored_pair_table_bytes(back), db.objects[0].pair_table->bytes() + db.objects[1].pair_table->bytes());
  // A load for the views' poses alone neither reads nor unpacks them; the rest is the same.
  test::TempDir dir;
  db.save(dir / "tables.vpdb");
  const ViewDatabase without = ViewDatabase::load(dir / "tables.vpdb", {.pair_tables = false});
  EXPECT_FALSE(without.objects[0].pair_table || without.objects[1].pair_table);
  EXPECT_EQ(without.serialize(), [&] {
    ViewDatabase stripped = db;
    for (DatabaseObject& o : stripped.objects) o.pair_table.reset();
    return stripped.serialize();
  }());
  EXPECT_TRUE(ViewDatabase::load(dir / "tables.vpdb").objects[1].pair_table);
  // Damage in the tables is found by the load that reads them; a cut file by both.
  std::vector<std::uint8_t> file = db.serialize();
  file[file.size() - 100] ^= 0x10;
  write_file_atomic(dir / "flipped.vpdb", file);
  expect_error([&] { ViewDatabase::load(dir / "flipped.vpdb"); }, "checksum mismatch in the pair tables");
  EXPECT_EQ(ViewDatabase::load(dir / "flipped.vpdb", {.pair_tables = false}).views.size(), db.views.size());
  file.resize(file.size() - 100);
  write_file_atomic(dir / "cut.vpdb", file);
  expect_error([&] { ViewDatabase::load(dir / "cut.vpdb"); }, "the pair tables' header says");
  expect_error([&] { ViewDatabase::load(dir / "cut.vpdb", {.pair_tables = false}); }, "truncated or padded");
  file.resize(20);
  write_file_atomic(dir / "header.vpdb", file);
  expect_error([&] { ViewDatabase::load(dir / "header.vpdb", {.pair_tables = false}); }, "not a viewpose view database");
  // Room for the smaller table alone: only it is stored; none at 0. The recognizer makes the rest.
  const std::vector<ObjectModel> models = {{1, "jug", make_jug()}, {5, "can", make_can()}};
  DatabaseParams p = db.params;
  const std::size_t jug = db.objects[0].pair_table->bytes(), can = db.objects[1].pair_table->bytes();
  ASSERT_NE(jug, can);
  p.max_pair_table_bytes = std::min(jug, can);
  const ViewDatabase limited = build_view_database(models, p);
  const std::size_t larger = jug > can ? 0 : 1;
  EXPECT_FALSE(limited.objects[larger].pair_table);
  EXPECT_TRUE(limited.objects[1 - larger].pair_table);
  EXPECT_EQ(ViewDatabase::deserialize(limited.serialize(), "limit.vpdb").params.max_pair_table_bytes, p.max_pair_table_bytes);
  p.max_pair_table_bytes = 0;
  EXPECT_EQ(stored_pair_table_bytes(build_view_database(models, p)), 0u);
  // Bad shaping options are refused before anything is rendered; a damaged table when read.
  p.ppf.angle_bins = 11;
  expect_error([&] { build_view_database(models, p); }, "ppf: bad options");
  ViewDatabase bad = small_db();
  auto table = std::make_shared<PpfTable>(*bad.objects[1].pair_table);
  table->entries.back() = PpfTable::entry(static_cast<std::uint32_t>(table->sampled.size()), 5);
  bad.objects[1].pair_table = table;
  expect_error([&] { ViewDatabase::deserialize(bad.serialize(), "table.vpdb"); },
               "table.vpdb: ppf: a pair table has a pair naming a point that does not exist");
}

TEST(ViewDatabaseTest, DamagedOrForeignFilesAreRefusedWithAClearError) {
  const std::vector<std::uint8_t> good = small_db().serialize();
  auto with = [&](auto&& edit) {
    std::vector<std::uint8_t> b = good;
    edit(b);
    return b;
  };
  expect_error([&] { ViewDatabase::deserialize({}, "empty.vpdb"); }, "empty.vpdb: not a viewpose view database");
  expect_error([&] { ViewDatabase::deserialize(test::to_bytes("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\n"), "a.vpdb"); },
               "not a viewpose view database");
  expect_error([&] { ViewDatabase::deserialize(with([](auto& b) { b[8] = 2; }), "v2.vpdb"); },
               "database format version 2, this viewpose reads version 4; rebuild it");
  expect_error([&] { ViewDatabase::deserialize(with([](auto& b) { std::swap(b[12], b[15]); }), "be.vpdb"); }, "byte order");
  expect_error([&] { ViewDatabase::deserialize(std::span(good.data(), good.size() / 2), "half.vpdb"); }, "truncated or padded");
  expect_error([&] { ViewDatabase::deserialize(with([](auto& b) { b[b.size() / 2] ^= 0x40; }), "flip.vpdb"); },
               "checksum mismatch");
  test::TempDir dir;
  expect_error([&] { ViewDatabase::load(dir / "missing.vpdb"); }, "missing.vpdb: no such file");
}

TEST(ViewDatabaseTest, TheFuzzersSeedFileIsADatabaseAndItsDamagedValuesAreRefused) {
  // fuzz/corpus/view_database/square_file, written by scripts/make-fuzz-seeds.py: a whole file
  // after the fuzz target's one mode byte. If the script and the format drift apart, the fuzzer
  // would start from inputs the reader refuses at once.
  const auto bytes = read_file_bytes(std::filesystem::path(VIEWPOSE_SOURCE_DIR) / "fuzz/corpus/view_database/square_file");
  ASSERT_GT(bytes.size(), 33u);
  std::vector<std::uint8_t> file(bytes.begin() + 1, bytes.end());
  const ViewDatabase db = ViewDatabase::deserialize(file, "square");
  ASSERT_EQ(db.objects.size(), 1u);
  EXPECT_EQ(db.objects[0].name, "square");
  EXPECT_EQ(db.objects[0].symmetries.discrete.size(), 1u);
  EXPECT_EQ(db.views.size(), 2u);
  EXPECT_EQ(db.views[1].described_points, 3u);
  EXPECT_EQ(db.views[1].icp_points.size(), 2u);
  // The seed with a stored ICP grid (5 cm cells) is read with it.
  const auto grid_seed = read_file_bytes(std::filesystem::path(VIEWPOSE_SOURCE_DIR) / "fuzz/corpus/view_database/grid_payload");
  const ViewDatabase with_grid = ViewDatabase::deserialize(ViewDatabase::file_from_payload(std::span(grid_seed).subspan(1)), "grid");
  ASSERT_EQ(with_grid.objects.size(), 1u);
  EXPECT_EQ(with_grid.objects[0].nearest_cells.size(), 32u);
  // And the seed with a stored pair table (two points, their two pairs) with it.
  // (Its first byte 2: four bytes of the payload's length, the payload, then the tables.)
  const auto table_seed = read_file_bytes(std::filesystem::path(VIEWPOSE_SOURCE_DIR) / "fuzz/corpus/view_database/pair_table_payload");
  ASSERT_EQ(table_seed[0], 2);
  std::uint32_t payload_bytes = 0;
  std::memcpy(&payload_bytes, table_seed.data() + 1, 4);
  const auto table_parts = std::span(table_seed).subspan(5);
  const ViewDatabase with_table = ViewDatabase::deserialize(
      ViewDatabase::file_from_payload(table_parts.first(payload_bytes), table_parts.subspan(payload_bytes)), "table");
  ASSERT_TRUE(with_table.objects[0].pair_table);
  EXPECT_EQ(with_table.objects[0].pair_table->entries.size(), 2u);
  EXPECT_FALSE(with_grid.objects[0].pair_table);
  // A value no build could write, with the checksum made right again: refused, by name.
  // The script's header is the library's.
  // (After the payload, the pair tables' 16-byte header: none stored.)
  const std::vector<std::uint8_t> payload(file.begin() + 32, file.end() - 16);
  EXPECT_EQ(ViewDatabase::file_from_payload(payload), file);
  const auto refused = [&](std::size_t offset, float value) {
    std::vector<std::uint8_t> bad_payload = payload;
    std::memcpy(bad_payload.data() + offset - 32, &value, sizeof value);
    const std::vector<std::uint8_t> bad = ViewDatabase::file_from_payload(bad_payload);
    try {
      ViewDatabase::deserialize(bad, "bad.vpdb");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  // The last view's last ICP point, and its first VFH bin.
  EXPECT_NE(refused(file.size() - 16 - 4, NAN).find("not a finite number"), std::string::npos);
  const std::size_t last_view_vfh = file.size() - 16 - (4 + 2 * 12) - 4 - 12 - 4 * 90 - 4 * 308;
  EXPECT_NE(refused(last_view_vfh, INFINITY).find("descriptor is not finite"), std::string::npos);
}

TEST(Matching, ChiSquaredDistance) {
  Vfh a{}, b{};
  a[0] = 3;
  b[0] = 1;  // (3-1)^2 / 4 = 1
  a[10] = 2;  // (2-0)^2 / 2 = 2
  EXPECT_FLOAT_EQ(chi_squared(a, b), 3.0f);
  EXPECT_FLOAT_EQ(chi_squared(a, a), 0.0f);
  EXPECT_FLOAT_EQ(chi_squared(a, b), chi_squared(b, a));
}

}  // namespace
}  // namespace viewpose

namespace viewpose {
namespace {

// A database of `objects` x `views` random sparse histograms, clustered around a few shapes as
// real views are, with some bins empty in every view (as PCL's f4 bins are).
ViewDatabase random_histograms(std::size_t objects, std::size_t views, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vfh> shapes(8);
  for (Vfh& h : shapes)
    for (std::size_t b = 0; b < h.size(); ++b) h[b] = (b >= 135 && b < 180) || u(rng) < 0.6f ? 0.0f : u(rng);
  ViewDatabase db;
  db.objects.resize(objects);
  for (std::size_t o = 0; o < objects; ++o)
    for (std::size_t v = 0; v < views; ++v) {
      ViewEntry e;
      e.object = static_cast<std::uint32_t>(o);
      const Vfh& shape = shapes[(o + v) % shapes.size()];
      for (std::size_t b = 0; b < e.vfh.size(); ++b) e.vfh[b] = shape[b] * (0.6f + 0.8f * u(rng));
      db.views.push_back(e);
    }
  return db;
}

TEST(ViewIndex, ASmallDatabaseGivesExactlyTheExhaustiveSearchesMatches) {
  const ViewDatabase db = random_histograms(50, 80, 1);
  const ViewIndex index(db, /*candidates=*/db.views.size());
  ASSERT_TRUE(index.exhaustive());
  EXPECT_TRUE(ViewIndex(db, db.views.size() / 2).exhaustive()) << "up to twice the candidates: searched in full";
  EXPECT_FALSE(ViewIndex(db, db.views.size() / 2 - 1).exhaustive());
  const ViewDatabase queries = random_histograms(1, 20, 2);
  for (const ViewEntry& q : queries.views) {
    const std::vector<Match> all = nearest_views_per_object(db, q.vfh, 20);
    const std::vector<Match> got = index.nearest(q.vfh, 20);
    ASSERT_EQ(got.size(), all.size());
    for (std::size_t k = 0; k < all.size(); ++k) {
      ASSERT_EQ(got[k].view, all[k].view) << k;
      ASSERT_EQ(got[k].distance, all[k].distance);
    }
    // Cut to the 120 nearest: the exhaustive answer's first 120.
    const std::vector<Match> cut = index.nearest(q.vfh, 20, 120);
    ASSERT_EQ(cut.size(), 120u);
    for (std::size_t k = 0; k < cut.size(); ++k) ASSERT_EQ(cut[k].view, all[k].view) << k;
  }
  EXPECT_TRUE(ViewIndex(ViewDatabase{}).nearest(queries.views[0].vfh, 20).empty());
}

TEST(ScaledDatabase, TheOriginalsKeepTheirIdsAndEachCopyFollowsItsOriginal) {
  // The jug (id 1) and the can (id 5), grown to five objects: the copies' ids are new (6, 7, 8),
  // object k is a copy of object k mod 2 (bench counts a copy found as its original by that), and
  // every view of a copy is its original's view, histogram reshaped.
  const ViewDatabase& small = small_db();
  const ViewDatabase db = scaled_database(small, 5, 4);
  ASSERT_EQ(db.objects.size(), 5u);
  const std::vector<int> ids = {1, 5, 6, 7, 8};
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(db.objects[k].id, ids[k]) << k;
    EXPECT_EQ(db.objects[k].diameter_m, small.objects[k % 2].diameter_m) << k;
  }
  // Each object's views in a block of its own, its original's in their order.
  const std::size_t per_object = small.views.size() / 2;
  ASSERT_EQ(db.views.size(), 5 * per_object);
  for (std::size_t k = 0; k < db.views.size(); ++k) {
    ASSERT_EQ(db.views[k].object, k / per_object) << k;
    EXPECT_EQ(db.views[k].crh, small.views[(k / per_object) % 2 * per_object + k % per_object].crh) << k;
  }
  for (std::size_t k = 0; k < small.views.size(); ++k) EXPECT_EQ(db.views[k].vfh, small.views[k].vfh) << "originals unchanged";
  EXPECT_NE(db.views[small.views.size()].vfh, small.views[0].vfh) << "a copy's histogram is reshaped";
}

TEST(ViewIndex, ALargeDatabaseFindsNearlyAllOfTheTrueNearestViews) {
  // 400 objects x 20 views of real histograms (the jug's and the can's, reshaped per repeat).
  const ViewDatabase db = scaled_database(small_db(), 400, 4);
  const ViewIndex index(db);
  ASSERT_FALSE(index.exhaustive());
  std::size_t found = 0, wanted = 0;
  for (std::size_t q = 0; q < small_db().views.size(); q += 4) {
    const Vfh& query = small_db().views[q].vfh;
    std::vector<Match> truth = nearest_views_per_object(db, query, 20);
    truth.resize(120);
    const std::vector<Match> got = index.nearest(query, 20, 120);
    ASSERT_EQ(got.size(), 120u);
    std::set<std::uint32_t> mine;
    for (const Match& m : got) mine.insert(m.view);
    for (const Match& m : truth) found += mine.count(m.view);
    wanted += truth.size();
    EXPECT_EQ(got[0].view, truth[0].view) << "the nearest view itself is never missed";
  }
  EXPECT_GE(static_cast<double>(found) / static_cast<double>(wanted), 0.95);
}

}  // namespace
}  // namespace viewpose
