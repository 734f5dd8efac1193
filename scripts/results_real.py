"""Real frames for `make results` (scripts/make-results.py): they lead the page, because the simulator
is not the world. Every run here drives only the `viewpose` command, as a user would.

- ycbv_real_dev: real YCB-Video Xtion frames in the BOP layout with ground truth (two scenes),
  recognized in open mode (any object, any number: false positives count) and as the BOP19 task
  (--targets), scored with ADD-S, ADD(-S) and BOP's Average Recall.
- ycbv_real_sample: two more frames of the first scene, ground truth moved into the BOP meshes' frame.
- pcl_mosd: ten real Kinect frames against a database of HOPE objects, none of which is in them:
  every detection is a false positive.
- pcl_kinect: PCL's Kinect scenes: the milk carton found from one scanned view of it, and the
  other scenes against the HOPE database as negatives.
- the same negatives against every YCB-V object ../shared holds in BOP's format (ten): household
  objects of the same kinds and sizes as those on the mOSD and PCL tables, none of them there.
"""
import json
import math
import shutil
import statistics
import time
from pathlib import Path

YCB_SAMPLE_NAMES = {8: "009_gelatin_box", 14: "025_mug", 21: "061_foam_brick"}
# HOPE grocery objects (2021): none of them is in the mOSD (2012) or the PCL (2012) scenes.
HOPE_NEGATIVES = [1, 2, 6, 11, 13, 14, 16, 17]
# Every YCB-V model in ../shared in BOP's format: ycbv_real_dev's seven and ycbv_real_sample's BOP meshes (the
# re-oriented OBJ meshes of ycb_meshes/, the soup can and the drill among them, are in another frame and unit).
YCBV_NEGATIVE_SOURCES = [("ycbv_real_dev/models", [1, 3, 8, 9, 11, 14, 21]), ("ycbv_real_sample/models_bop_ycbv", [2, 5, 12])]
PCL_NEGATIVE_SCENES = ["office1.pcd", "table_scene_mug_stereo_textured.pcd", "grabber_sequences/pcd/frame_20121214T142255.814212.pcd",
                       "grabber_sequences/pcd/frame_20121214T142256.068683.pcd",
                       "grabber_sequences/pcd/frame_20121214T142256.332395.pcd"]


def read_details(path):
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def percentile(values, q):
    """Nearest-rank percentile (q in 0..100) of a non-empty list."""
    v = sorted(values)
    return v[max(0, min(len(v) - 1, math.ceil(q / 100 * len(v)) - 1))]


def time_summary(ms):
    return {"median": statistics.median(ms), "p95": percentile(ms, 95), "max": max(ms), "frames": len(ms)}


def subset_models(src, dst, ids):
    """A models folder of symlinks to some of src's obj_NNNNNN.ply (and its models_info.json)."""
    if dst.exists():
        shutil.rmtree(dst)
    dst.mkdir(parents=True)
    for f in sorted(src.glob("obj_*.ply")):
        if ids is None or int(f.stem[4:]) in ids:
            (dst / f.name).symlink_to(f)
    if (src / "models_info.json").exists():
        (dst / "models_info.json").symlink_to(src / "models_info.json")
    return dst


def bop_run(run, db, dataset, work, tag, split="test", targets=None):
    """viewpose bop (open mode, or the BOP19 task with targets) + viewpose eval --json."""
    csv, details, ev = work / f"{tag}.csv", work / f"{tag}.jsonl", work / f"{tag}_eval.json"
    extra = ["--targets", targets] if targets else []
    run("bop", "--db", db, "--dataset", dataset, "--split", split, "-o", csv, "--details", details, *extra)
    run("eval", "--dataset", dataset, "--split", split, "--results", csv, "--json", ev, *extra)
    d = read_details(details)
    return {"eval": json.loads(ev.read_text()), "details": d, "time_ms": time_summary([x["times_ms"]["total"] for x in d])}


def ycbv_dev(run, shared, work):
    ds = shared / "data" / "ycbv_real_dev"
    if not ds.is_dir():
        return None
    db = work / "ycbv_dev.vpdb"
    run("db", "build", "--bop-models", ds / "models", "--unit", "mm", "-o", db)
    targets = next((ds / n for n in ("test_targets_bop19.json", "test_targets.json") if (ds / n).exists()), None)
    out = {"open": bop_run(run, db, ds, work, "ycbv_dev_open")}
    if targets:
        out["task"] = bop_run(run, db, ds, work, "ycbv_dev_task", targets=targets)
        out["targets_file"] = targets.name
    return out


def ycbv_sample_dataset(shared, work):
    """A copy of the YCB-Video sample whose ground truth is moved into the BOP meshes' frame.

    The sample's poses are in the YCB-Video model frame (points.xyz); the BOP meshes are those models
    moved so that their bounding box is centred (MANIFEST: a few mm). With c the centre of
    points.xyz's box, p_ycb = p_bop + c, so T_camera_bop = T_camera_ycb * translation(c)."""
    src = shared / "data" / "ycbv_real_sample"
    dst = work / "ycbv"
    if dst.exists():
        shutil.rmtree(dst)
    (dst / "data" / "0000").mkdir(parents=True)
    shutil.copytree(src / "models_bop_ycbv", dst / "models")
    for f in (src / "data" / "0000").glob("*-depth.png"):
        (dst / "data" / "0000" / f.name).symlink_to(f)
    shutil.copy(src / "data" / "0000" / "scene_camera.json", dst / "data" / "0000")
    centres = {}
    for obj_id, name in YCB_SAMPLE_NAMES.items():
        pts = [tuple(map(float, l.split())) for l in (src / "models" / name / "points.xyz").read_text().split("\n") if l.strip()]
        centres[obj_id] = [1000 * 0.5 * (min(p[k] for p in pts) + max(p[k] for p in pts)) for k in range(3)]  # mm
    gt = json.loads((src / "data" / "0000" / "scene_gt.json").read_text())
    for entries in gt.values():
        for e in entries:
            c = centres.get(e["obj_id"])
            if c is None:
                continue
            R = e["cam_R_m2c"]
            e["cam_t_m2c"] = [e["cam_t_m2c"][i] + sum(R[3 * i + k] * c[k] for k in range(3)) for i in range(3)]
    (dst / "data" / "0000" / "scene_gt.json").write_text(json.dumps(gt, indent=1))
    return dst, centres


def ycbv_sample(run, shared, work):
    if not (shared / "data" / "ycbv_real_sample").is_dir():
        return None
    ds, centres = ycbv_sample_dataset(shared, work)
    out = {"centres_mm": centres, "runs": {}}
    # The three objects in the frames, then all six meshes the sample has (three of them absent).
    for label, ids in (("3 objects", [8, 14, 21]), ("6 objects", None)):
        n = label.split()[0]
        models = subset_models(ds / "models", work / f"ycb_models_{n}", ids)
        db = work / f"ycb_{n}.vpdb"
        run("db", "build", "--bop-models", models, "--unit", "mm", "-o", db)
        out["runs"][label] = bop_run(run, db, ds, work, f"ycb_{n}", split="data")
    return out


def recognize_each(run, db, scenes, work, tag):
    """viewpose recognize --json on each scene file; one record per frame."""
    frames = []
    for i, scene in enumerate(scenes):
        path = work / f"{tag}_{i}.json"
        start = time.monotonic()
        run("recognize", "--db", db, scene, "--json", path)
        process_ms = 1000 * (time.monotonic() - start)  # start to exit: reading the database and the scene too
        r = json.loads(path.read_text())
        frames.append({"scene": scene, "detections": r["detections"], "time_ms": r["times_ms"]["total"],
                       "process_ms": process_ms, "hypotheses": r["hypotheses"], "clusters": r["clusters"]})
    return frames


def hope_database(run, shared, work):
    db = work / "hope8.vpdb"
    models = subset_models(shared / "data" / "hope_models", work / "hope8_models", HOPE_NEGATIVES)
    run("db", "build", "--bop-models", models, "--unit", "mm", "-o", db)
    return db


def ycbv_database(run, shared, work):
    """The YCB-V objects of YCBV_NEGATIVE_SOURCES in one database; None where a source is missing."""
    dst = work / "ycbv_negatives_models"
    if dst.exists():
        shutil.rmtree(dst)
    dst.mkdir(parents=True)
    info = {}
    for folder, ids in YCBV_NEGATIVE_SOURCES:
        src = shared / "data" / folder
        if not (src / "models_info.json").exists():
            return None
        known = json.loads((src / "models_info.json").read_text())
        for i in ids:
            ply = src / f"obj_{i:06d}.ply"
            if not ply.exists() or str(i) not in known:
                return None
            (dst / ply.name).symlink_to(ply)
            info[str(i)] = known[str(i)]
    (dst / "models_info.json").write_text(json.dumps(info))
    db = work / "ycbv_negatives.vpdb"
    run("db", "build", "--bop-models", dst, "--unit", "mm", "-o", db)
    return db


def negatives(run, shared, work, database="hope"):
    """mOSD and PCL Kinect frames against objects none of which is in them (the HOPE ones, or YCB-V's):
    every detection is a false positive."""
    mosd = sorted((shared / "data" / "pcl_mosd" / "test").glob("*.pcd"), key=lambda p: int(p.stem[4:]))
    kinect = shared / "data" / "pcl_kinect"
    if not mosd and not kinect.is_dir():
        return None
    if database == "hope":
        db, objects = hope_database(run, shared, work), len(HOPE_NEGATIVES)
    else:
        db, objects = ycbv_database(run, shared, work), sum(len(ids) for _, ids in YCBV_NEGATIVE_SOURCES)
        if db is None:
            return None
    out = {"database": database, "objects": objects}
    out["mosd"] = recognize_each(run, db, mosd, work, f"mosd_{database}") if mosd else []
    pcl = [kinect / s for s in PCL_NEGATIVE_SCENES if (kinect / s).exists()]
    out["pcl"] = recognize_each(run, db, pcl, work, f"pcl_negative_{database}") if pcl else []
    return out


def milk(run, shared, work):
    """The thesis's other way to fill a database: one view scanned with the sensor (PCL's milk.pcd),
    found in the Kinect scene it came from. No ground truth: the points' fit is what is measured."""
    kinect = shared / "data" / "pcl_kinect"
    if not (kinect / "milk.pcd").exists():
        return None
    db = work / "milk.vpdb"
    if db.exists():
        db.unlink()
    run("db", "add-view", kinect / "milk.pcd", "--object", "milk", "--db", db)
    return recognize_each(run, db, [kinect / "milk_cartoon_all_small_clorox.pcd"], work, "milk")[0]


def run_all(run, shared, work):
    return {"dev": ycbv_dev(run, shared, work), "sample": ycbv_sample(run, shared, work),
            "negatives": negatives(run, shared, work), "negatives_ycbv": negatives(run, shared, work, "ycbv"),
            "milk": milk(run, shared, work)}


# ---- the page ------------------------------------------------------------------------------------

def plot_precision_recall(curves, out_png, title):
    """Precision against recall as the detection score's threshold falls (eval --json pr_curve), one line a run."""
    import matplotlib.pyplot as plt  # make-results.py chose the backend
    fig, ax = plt.subplots(figsize=(6, 4), dpi=100)
    for label, curve in curves.items():
        if curve:
            ax.plot([100 * p["recall"] for p in curve], [100 * p["precision"] for p in curve], ".-", ms=3, label=label)
    ax.set_xlabel("recall (%): right poses (ADD-S) among the targets")
    ax.set_ylabel("precision (%): right among those kept")
    ax.set_xlim(0, 102)
    ax.set_ylim(0, 102)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(out_png)
    plt.close(fig)


def pct(x):
    return f"{100 * x:.0f} %"


def ar_cells(s):
    """AR, VSD, MSSD, MSPD of a score row, or dashes when eval gave none."""
    if "ar" not in s:
        return "— | — | — | —"
    return f"{s['ar']:.3f} | {s['ar_vsd']:.3f} | {s['ar_mssd']:.3f} | {s['ar_mspd']:.3f}"


def times_cell(t):
    return f"{t['median'] / 1000:.2f} / {t['p95'] / 1000:.2f} / {t['max'] / 1000:.2f} s"


def scene_times(details, scene):
    return time_summary([d["times_ms"]["total"] for d in details if d["scene_id"] == scene])


def headline(real):
    """The numbers the README leads with, to compare with the next run's."""
    h = {}
    dev = real.get("dev")
    if dev:
        a = dev["open"]["eval"]["all"]
        h["ycbv_dev_recall_add_s"] = a["recall_add_s"]
        h["ycbv_dev_false_positives"] = a["false_positives"]
        h["ycbv_dev_median_s"] = dev["open"]["time_ms"]["median"] / 1000
        if "task" in dev and "ar" in dev["task"]["eval"]["all"]:
            h["ycbv_dev_ar"] = dev["task"]["eval"]["all"]["ar"]
    s = real.get("sample")
    if s:
        r3 = s["runs"]["3 objects"]
        h["ycbv_sample_recall_add_s"] = r3["eval"]["all"]["recall_add_s"]
        h["ycbv_sample_false_positives"] = r3["eval"]["all"]["false_positives"] + s["runs"]["6 objects"]["eval"]["all"]["false_positives"]
        h["ycbv_sample_max_s"] = r3["time_ms"]["max"] / 1000
    n = real.get("negatives")
    if n and n["mosd"]:
        h["mosd_detections"] = sum(len(f["detections"]) for f in n["mosd"])
        h["mosd_max_s"] = max(f["time_ms"] for f in n["mosd"]) / 1000
    n = real.get("negatives_ycbv")
    if n and n["mosd"]:
        h["negatives_ycbv_detections"] = sum(len(f["detections"]) for f in n["mosd"] + n["pcl"])
    return h


# Which way is better for each headline number.
HIGHER_IS_BETTER = {"ycbv_dev_recall_add_s", "ycbv_dev_ar", "ycbv_sample_recall_add_s", "seed_recall_add_s", "seed_recall_add",
                    "room_recall_add_s", "seed_room_recall_add_s"}


def worse_than_before(now, before):
    """Lines naming every headline number that is worse than in the previous run's headline.json."""
    lines = []
    for key, value in now.items():
        if key not in before or key == "source":
            continue
        old = before[key]
        if key in HIGHER_IS_BETTER:
            worse = value < old - 1e-9
        elif key.endswith("_s") or key.endswith("_ms"):
            worse = value > 1.1 * old  # this machine's timings move by up to 10 % from run to run
        else:
            worse = value > old  # counts of false positives
        if worse:
            lines.append(f"- **worse**: `{key}` is {value:.3g}, was {old:.3g} ({before.get('source', 'the previous run')})")
    return lines


def write_real(w, real):
    dev = real.get("dev")
    w("## Real frames: YCB-Video, Asus Xtion (`ycbv_real_dev`)\n")
    if not dev:
        w("Skipped: ../shared/data/ycbv_real_dev is not there.\n")
    else:
        ev_open, ev_task = dev["open"]["eval"], dev.get("task", {}).get("eval")
        w("Nine real frames in the BOP layout with ground truth: video 0000 frames 3-10 (a gelatin box, a mug and a foam")
        w("brick on a desk, the mug and the brick touching, about 0.6 m) and video 0014 frame 2 (another desk: a")
        w("master chef can, a sugar box, a potted meat can and a pitcher, objects 1, 3, 9, 11, about 0.9 m). The database holds all seven")
        w("objects (BOP YCB-V meshes, 80 views each). *Open mode* is `viewpose bop` as a robot would run it: any object,")
        w("any number, so every pose that is not right is a false positive (ADD-S above 10 % of the diameter). *BOP19")
        w(f"task* is `bop --targets {dev.get('targets_file', '')}`: each image's objects and counts are given, at most")
        w("that many estimates per object; BOP's Average Recall (AR = mean of VSD, MSSD and MSPD recall, the BOP toolkit's")
        w("definitions, `viewpose eval --targets`) is scored there, as the BOP challenge scores it.\n")
        w("| scene | targets | ADD-S | ADD(-S) | AR | AR VSD | AR MSSD | AR MSPD | false positives (open) | per frame | time per frame (median / p95 / max) |")
        w("|---|---|---|---|---|---|---|---|---|---|---|")
        for scene, so in sorted(ev_open["per_scene"].items(), key=lambda kv: int(kv[0])):
            st = ev_task["per_scene"].get(scene, {}) if ev_task else {}
            frames = sum(1 for d in dev["open"]["details"] if d["scene_id"] == int(scene))
            w(f"| {int(scene):06d} | {so['targets']} | {pct(so['recall_add_s'])} | {pct(so['recall_add_or_s'])} | {ar_cells(st)} | "
              f"{so['false_positives']} | {so['false_positives'] / max(frames, 1):.1f} | {times_cell(scene_times(dev['open']['details'], int(scene)))} |")
        a, at = ev_open["all"], ev_task["all"] if ev_task else {}
        frames = len(dev["open"]["details"])
        w(f"| all | {a['targets']} | **{pct(a['recall_add_s'])}** | {pct(a['recall_add_or_s'])} | {ar_cells(at)} | "
          f"**{a['false_positives']}** | {a['false_positives'] / max(frames, 1):.1f} | {times_cell(dev['open']['time_ms'])} |\n")
        if ev_task:
            w(f"In the BOP19 task the same frames give ADD-S {pct(ev_task['all']['recall_add_s'])} with "
              f"{ev_task['all']['false_positives']} false positives among the estimates kept "
              f"({times_cell(dev['task']['time_ms'])} per frame). For scale: the best classical depth-only method of the BOP")
            w("challenge (Vidal et al. 2018, point pair features) reports an AR of about 0.58 on LM-O; these nine frames")
            w("are far too few for a published number, but they are scored the same way.\n")
            t = ev_task["all"]
            if "ar" in t and t["ar_vsd"] - t["ar_mssd"] > 0.3:
                w(f"AR_MSSD ({t['ar_mssd']:.2f}) and AR_MSPD ({t['ar_mspd']:.2f}) lie far below AR_VSD ({t['ar_vsd']:.2f}): most poses")
                w("with the right surface are another of the shape's equivalent poses (a box turned half a turn, a can upside")
                w("down), which BOP's symmetries do not list because the printing tells them apart. Depth alone cannot; viewpose")
                w("finds each mesh's symmetries from its shape and reports one canonical pose among them, which is the")
                w("annotated one only by chance. VSD compares visible surfaces and does not mind.\n")
        w("Precision against recall as the threshold on the detection score falls (the points of `eval --json`'s")
        w("`pr_curve`): where the curve drops, high-scoring poses are wrong, and no threshold removes them.\n")
        w("![precision against recall](results/precision_recall.png)\n")
        w("| object | targets | ADD-S | ADD | ADD(-S) | AR (task) | false positives (open) | mean translation error |")
        w("|---|---|---|---|---|---|---|---|")
        for obj, sc in sorted(ev_open["per_object"].items(), key=lambda kv: int(kv[0])):
            ar = ev_task["per_object"].get(obj, {}).get("ar") if ev_task else None
            w(f"| {obj} | {sc['targets']} | {pct(sc['recall_add_s'])} | {pct(sc['recall_add'])} | {pct(sc['recall_add_or_s'])} | "
              f"{'—' if ar is None else f'{ar:.3f}'} | {sc['false_positives']} | {sc['translation_error_mm']['mean']:.1f} mm |")
        w("")

    s = real.get("sample")
    w("## Real frames: `ycbv_real_sample`\n")
    if not s:
        w("Skipped: ../shared/data/ycbv_real_sample is not there.\n")
    else:
        c = s["centres_mm"]
        w("Two real frames (video 0000 frames 1-2, the first scene above, seen a few frames earlier) with a gelatin box, a")
        w("mug and a foam brick. The ground truth is in the YCB-Video model frame; the BOP meshes are those models")
        w("re-centred, so the truth is moved by the centre of each `points.xyz` box (mm: " +
          ", ".join(f"{k}: ({v[0]:.1f}, {v[1]:.1f}, {v[2]:.1f})" for k, v in sorted(c.items())) + ") before scoring.")
        w("Depth alone cannot tell these three objects' sides apart (the box is a plain box, the mug's handle is out of")
        w("sight, the brick nearly square), so the surface is right (ADD-S) while ADD fails. The second database adds")
        w("three YCB-V objects that are not in view (2, 5, 12): whatever it reports of them is a false positive.\n")
        w("| database | targets | ADD-S | ADD | ADD(-S) | MSSD | false positives | time per frame (median / p95 / max) |")
        w("|---|---|---|---|---|---|---|---|")
        for label, r in s["runs"].items():
            a = r["eval"]["all"]
            w(f"| {label} | {a['targets']} | {pct(a['recall_add_s'])} | {pct(a['recall_add'])} | {pct(a['recall_add_or_s'])} | "
              f"{pct(a['recall_mssd'])} | {a['false_positives']} | {times_cell(r['time_ms'])} |")
        w("")

    n = real.get("negatives")
    w("## Real frames with nothing known in them: mOSD and PCL Kinect scenes\n")
    if not n:
        w("Skipped: ../shared/data/pcl_mosd and pcl_kinect are not there.\n")
    for n in (real.get("negatives"), real.get("negatives_ycbv")):
        if not n:
            continue
        if n["database"] == "hope":
            w(f"The database holds {n['objects']} HOPE grocery objects (a soup can, five bottles, a box, two cartons; ids "
              f"{', '.join(map(str, HOPE_NEGATIVES))}), none of which is in these frames: every detection is a false positive.")
            w("mOSD: ten real Kinect frames of boxes, cylinders and mixed piles on a table (PCL's mOSD test scenes); then the")
            w("other PCL Kinect scenes. A robot looking around sees such frames far more often than frames with its objects.\n")
        else:
            ids = ", ".join(str(i) for _, group in YCBV_NEGATIVE_SOURCES for i in group)
            w(f"### The same frames against {n['objects']} YCB-V objects\n")
            w(f"Every YCB-V object ../shared holds in BOP's format (ids {ids}: cans, boxes, a pitcher, a mug, two bottles, a brick),")
            w("household things of the same kinds and sizes as those on these tables, none of them there. A detection here is")
            w("a false positive too, though it may be a look-alike that depth alone cannot tell apart (a box of nearly the same")
            w("size).\n")
        w("| frame | clusters | poses tried | detections (all false) | frame time | process |")
        w("|---|---|---|---|---|---|")
        for f in n["mosd"] + n["pcl"]:
            name = Path(f["scene"]).name
            dets = ", ".join(f"{d['object_name']} ({d['score']:.2f})" for d in f["detections"]) or "none"
            w(f"| {name} | {f['clusters']} | {f['hypotheses']} | {len(f['detections'])}: {dets} | {f['time_ms'] / 1000:.2f} s | "
              f"{f['process_ms'] / 1000:.2f} s |")
        for label, frames in (("mOSD", n["mosd"]), ("PCL Kinect", n["pcl"])):
            if frames:
                t = time_summary([f["time_ms"] for f in frames])
                fp = sum(len(f["detections"]) for f in frames)
                p = time_summary([f["process_ms"] for f in frames])
                w(f"\n{label}: **{fp} false positives** in {len(frames)} frames ({fp / len(frames):.1f} per frame); time per "
                  f"frame {times_cell(t)}, whole process {times_cell(p)} (median / p95 / max).")
        w("")
    m = real.get("milk")
    if m:
        w("### PCL's milk carton from one scanned view\n")
        w("`db add-view milk.pcd` (13,704 points of the carton, scanned with the Kinect), then `recognize` on the scene it")
        w("came from (milk_cartoon_all_small_clorox.pcd: the carton among other cartons and a Clorox bottle). milk.pcd")
        w("was cut out of this very frame, in the camera's coordinates, so the right pose is the identity.\n")
        for d in m["detections"]:
            t, R = d["t_m"], d["R"]
            angle = math.degrees(math.acos(max(-1.0, min(1.0, (R[0] + R[4] + R[8] - 1) / 2))))
            w(f"- {d['object_name']}: {1000 * math.hypot(*t):.1f} mm and {angle:.2f}° from the identity, score {d['score']:.2f}, "
              f"ICP RMS {1000 * d['icp_rmse_m']:.1f} mm")
        if not m["detections"]:
            w("- nothing found")
        w(f"\n{m['clusters']} clusters, {m['hypotheses']} poses tried, {m['time_ms']:.0f} ms; the whole `recognize` process "
          f"(reading the database and the scene, writing the JSON) {m['process_ms']:.0f} ms.\n")
