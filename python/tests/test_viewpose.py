"""The Python module against the command and the ground truth of simulated frames.

Run by `make test` (ctest's python.pytest) with PYTHONPATH at the built module, VIEWPOSE_CLI the
built command and VIEWPOSE_WORK a scratch folder.
"""
import gc
import json
import os
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest

import viewpose

CLI = os.environ.get("VIEWPOSE_CLI", "viewpose")
WORK = Path(os.environ.get("VIEWPOSE_WORK", "/tmp/viewpose-pytest"))


def run(*args):
    subprocess.run([CLI, *map(str, args)], check=True, capture_output=True, text=True)


@pytest.fixture(scope="module")
def scene():
    """A can database written by the command, and simulated Kinect frames of the can (one scene
    per distance, seeded) with their ground truth."""
    WORK.mkdir(parents=True, exist_ok=True)
    db = WORK / "can.vpdb"
    ds = WORK / "can_frames"
    run("db", "build", "can", "-o", db)
    run("simulate", "--preset", "seed-experiment", "--model", "can", "--orientations", "2",
        "--distances", "0.8", "1.2", "--seed", "7", "-o", ds)
    camera = json.loads((ds / "camera.json").read_text())
    frames = []
    for scene_dir in sorted((ds / "test").iterdir()):
        gt = json.loads((scene_dir / "scene_gt.json").read_text())
        for png in sorted((scene_dir / "depth").glob("*.png")):
            frames.append((png, gt[str(int(png.stem))][0]))
    K = (camera["fx"], camera["fy"], camera["cx"], camera["cy"])
    return {"db": db, "camera": ds / "camera.json", "K": K, "scale": camera["depth_scale"], "frames": frames}


def test_a_frame_gives_exactly_what_the_command_gives(scene):
    rec = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]))
    for png, _ in scene["frames"]:
        out = WORK / (png.stem + ".json")
        run("recognize", "--db", scene["db"], "--camera", scene["camera"], png, "--json", out, "--no-times")
        expected = json.loads(out.read_text())["detections"]
        got = rec.recognize(viewpose.read_depth_png(png), K=scene["K"], depth_scale=scene["scale"])
        assert len(got) == len(expected), png
        everything = json.loads(out.read_text())
        del everything["scene"]
        assert json.loads(got.to_json(with_times=False)) == everything
        for d, e in zip(got, expected):
            assert d.object_id == e["object_id"] and d.object_name == e["object_name"]
            assert d.score == e["score"]
            T = d.T_camera_object
            assert T.shape == (4, 4) and T.dtype == np.float64
            np.testing.assert_array_equal(T[:3, :3].reshape(-1), np.array(e["R"]))
            np.testing.assert_array_equal(T[:3, 3], np.array(e["t_m"]))
            np.testing.assert_array_equal(T[3], [0, 0, 0, 1])


def test_the_poses_are_the_ground_truths(scene):
    rec = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]))
    for png, gt in scene["frames"]:
        r = rec.recognize(viewpose.read_depth_png(png), K=scene["K"], depth_scale=scene["scale"])
        assert [d.object_id for d in r] == [1], png
        t_true = np.array(gt["cam_t_m2c"]) / 1000.0
        # The can is symmetric about its axis: its position and axis are what a pose can get right.
        assert np.linalg.norm(r[0].T_camera_object[:3, 3] - t_true) < 0.01
        axis_true = np.array(gt["cam_R_m2c"]).reshape(3, 3)[:, 2]
        assert abs(r[0].T_camera_object[:3, 2] @ axis_true) > np.cos(np.radians(5))
        assert 0.5 < r[0].score <= 1.0
        assert r.times_ms["total"] > 0 and not r.cut_short


def test_a_pose_below_min_score_is_no_detection_but_is_told(scene):
    png, _ = scene["frames"][0]
    depth = viewpose.read_depth_png(png)
    found = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"])).recognize(depth, K=scene["K"], depth_scale=scene["scale"])
    assert [d.object_id for d in found] == [1]
    # No pose is certain: with min_score 1 nothing is reported, and the nearest is told, where it was found.
    r = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]), min_score=1.0).recognize(depth, K=scene["K"], depth_scale=scene["scale"])
    assert len(r) == 0
    b = r.best_below_min_score
    assert b is not None and b.object_id == 1 and 0.5 < b.score < 1.0
    assert np.linalg.norm(b.T_camera_object[:3, 3] - found[0].T_camera_object[:3, 3]) < 0.005
    assert json.loads(r.to_json(with_times=False))["best_below_min_score"]["score"] == b.score


def test_the_counters_are_the_jsons(scene):
    rec = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]))
    png, _ = scene["frames"][0]
    r = rec.recognize(viewpose.read_depth_png(png), K=scene["K"], depth_scale=scene["scale"])
    j = json.loads(r.to_json(with_times=False))
    counters = ("clusters", "hypotheses", "repeats", "screened", "screened_out", "screened_merged", "regions", "parts_unreached",
                "split_clusters", "joined_regions", "grown_regions", "voted_regions", "dropped_as_explained", "dropped_inside_planes",
                "lifted_out_of_planes", "icp_steps")
    for name in counters:
        assert getattr(r, name) == j[name], name
    assert r.clusters >= 1 and r.hypotheses >= 1 and r.icp_steps >= r.hypotheses


def test_metres_as_float_give_the_same_as_millimetres_with_a_scale(scene):
    rec = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]))
    png, _ = scene["frames"][0]
    units = viewpose.read_depth_png(png)
    assert units.dtype == np.uint16 and units.shape == (480, 640)
    metres = (units * (scene["scale"] / 1000.0)).astype(np.float32)
    metres[units == 0] = np.nan
    a = rec.recognize(units, K=scene["K"], depth_scale=scene["scale"])
    b = rec.recognize(metres, K=scene["K"])
    assert len(a) == len(b) == 1
    np.testing.assert_allclose(a[0].T_camera_object, b[0].T_camera_object, atol=1e-6)


def test_a_budget_of_starting_poses_is_an_option(scene):
    db = viewpose.ViewDatabase.load(scene["db"])
    png, _ = scene["frames"][0]
    depth = viewpose.read_depth_png(png)
    for budget in (0, 4):  # every starting pose, and the best four
        assert len(viewpose.Recognizer(db, budget=budget).recognize(depth, K=scene["K"])) == 1
    # Coarse fit order only, and up to 16 screened by a short ICP once the first batch of 4 fails
    # (a budget of 8 leaves room for it).
    unscreened = viewpose.Recognizer(db, budget=8, screen=0).recognize(depth, K=scene["K"])
    assert len(unscreened) == 1 and unscreened.screened == 0
    screened = viewpose.Recognizer(db, budget=8, screen=16).recognize(depth, K=scene["K"])
    assert len(screened) == 1 and screened.screened <= 16 * screened.regions
    assert screened.screened_out + screened.screened_merged <= screened.screened
    assert unscreened.screened_out == unscreened.screened_merged == 0
    with pytest.raises(TypeError):
        viewpose.Recognizer(db, budget=-1)
    with pytest.raises(TypeError):
        viewpose.Recognizer(db, screen=-1)


def test_starting_poses_from_point_pair_votes_are_an_option(scene):
    db = viewpose.ViewDatabase.load(scene["db"])
    png, gt = scene["frames"][0]
    depth = viewpose.read_depth_png(png)
    t_true = np.array(gt["cam_t_m2c"]) / 1000.0
    for source in ("ppf", "both", "touching"):
        r = viewpose.Recognizer(db, source=source).recognize(depth, K=scene["K"], depth_scale=scene["scale"])
        assert [d.object_id for d in r] == [1], source
        assert np.linalg.norm(r[0].T_camera_object[:3, 3] - t_true) < 0.01, source
    with pytest.raises(ValueError, match="vfh, ppf, both, touching"):
        viewpose.Recognizer(db, source="sift")
    # Without its pair tables (as `recognize --source vfh` reads it), the same poses: a recognizer
    # that votes makes the tables it needs.
    bare = viewpose.ViewDatabase.load(scene["db"], pair_tables=False)
    r = viewpose.Recognizer(bare, source="touching").recognize(depth, K=scene["K"], depth_scale=scene["scale"])
    assert [d.object_id for d in r] == [1]


def test_the_recognizer_keeps_its_database(scene):
    rec = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]), matches=10)
    gc.collect()
    png, _ = scene["frames"][0]
    assert len(rec.recognize(viewpose.read_depth_png(png), K=scene["K"])) == 1


def test_a_database_built_in_python_is_the_commands(scene):
    db = viewpose.build_database(["can"])
    assert [(o.id, o.name) for o in db.objects] == [(1, "can")]
    assert db.view_count == viewpose.ViewDatabase.load(scene["db"]).view_count == 80
    db.save(WORK / "python_can.vpdb")
    assert (WORK / "python_can.vpdb").read_bytes() == scene["db"].read_bytes()


def test_mistakes_are_errors_with_the_commands_messages(scene):
    with pytest.raises(viewpose.Error, match="no-such.vpdb"):
        viewpose.ViewDatabase.load(WORK / "no-such.vpdb")
    with pytest.raises(viewpose.Error, match="not a PNG"):
        viewpose.read_depth_png(scene["camera"])
    rec = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]))
    with pytest.raises(viewpose.Error, match="2-D"):
        rec.recognize(np.zeros((4, 4, 3), np.uint16), K=scene["K"])
    with pytest.raises(viewpose.Error, match="uint16"):
        rec.recognize(np.zeros((480, 640), np.uint8), K=scene["K"])
    with pytest.raises(viewpose.Error, match="metres"):
        rec.recognize(np.zeros((480, 640), np.float32), K=scene["K"], depth_scale=1.0)
    with pytest.raises(viewpose.Error, match="unit"):
        viewpose.build_database(["can"], unit="inch")
    with pytest.raises(TypeError):
        viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]), no_such_option=1)
    assert issubclass(viewpose.Error, RuntimeError)


def test_a_wrong_depth_scale_is_warned_about(scene):
    rec = viewpose.Recognizer(viewpose.ViewDatabase.load(scene["db"]))
    png, _ = scene["frames"][0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rec.recognize(viewpose.read_depth_png(png), K=scene["K"], depth_scale=10.0)
    # 10 mm per unit puts the can 8-12 m away; 1 brings it back.
    assert any("depth_scale=1 " in str(w.message) for w in caught), [str(w.message) for w in caught]
