#!/usr/bin/env python3
"""Writes the small seed corpus the fuzzers start from (fuzz/corpus/<target>/). Deterministic:
rerunning it gives the same files. Standard library only."""
import json
import pathlib
import struct
import zlib

root = pathlib.Path(__file__).resolve().parent.parent / "fuzz" / "corpus"
points = [(0.1 * i, -0.05 * i, 0.8 + 0.01 * i) for i in range(6)]


def pcd_header(fields, sizes, types, width, height, data):
    n = width * height
    return (f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {' '.join(fields)}\n"
            f"SIZE {' '.join(map(str, sizes))}\nTYPE {' '.join(types)}\nCOUNT {' '.join('1' * len(fields))}\n"
            f"WIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n").encode()


def lzf_literal(raw):
    """An LZF stream of literal runs only (control byte = run length - 1, at most 32)."""
    out = bytearray()
    for i in range(0, len(raw), 32):
        chunk = raw[i:i + 32]
        out.append(len(chunk) - 1)
        out += chunk
    return bytes(out)


def write(target, name, data):
    d = root / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data)


# PCD
xyz = ["x", "y", "z"]
write("pcd", "ascii.pcd", pcd_header(xyz, [4] * 3, "FFF", 6, 1, "ascii")
      + b"".join(f"{x} {y} {z}\n".encode() for x, y, z in points))
write("pcd", "ascii_nan_organized.pcd", pcd_header(xyz + ["rgb"], [4] * 4, "FFFF", 3, 2, "ascii")
      + b"nan nan nan 0\n" + b"".join(f"{x} {y} {z} 4.2108e+06\n".encode() for x, y, z in points[:5]))
write("pcd", "v06_padding.pcd", b"VERSION .6\nFIELDS x y z _ label\nSIZE 4 4 4 1 4\nTYPE F F F U U\n"
      b"COUNT 1 1 1 3 1\nWIDTH 2\nHEIGHT 1\nDATA ascii\n1 2 3 0 0 0 7\n4 5 6 1 1 1 9\n")
fields = xyz + ["normal_x", "normal_y", "normal_z", "label"]
rec = lambda p: struct.pack("<6fI", *p, 0.0, 0.0, 1.0, 3)
write("pcd", "binary.pcd", pcd_header(fields, [4] * 7, "FFFFFFU", 6, 1, "binary") + b"".join(map(rec, points)))
raw = b"".join(struct.pack("<6f", *[p[k] for p in points]) for k in range(3))
packed = lzf_literal(raw)
write("pcd", "compressed.pcd", pcd_header(xyz, [4] * 3, "FFF", 6, 1, "binary_compressed")
      + struct.pack("<II", len(packed), len(raw)) + packed)

# PLY
tris = [(0, 1, 2), (0, 2, 3), (3, 4, 5)]
def ply(fmt, body):
    return (f"ply\nformat {fmt} 1.0\ncomment seed\nelement vertex {len(points)}\nproperty float x\n"
            "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
            f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n").encode() + body
write("ply", "ascii.ply", ply("ascii", b"".join(f"{x} {y} {z} 255 0 0\n".encode() for x, y, z in points)
                              + b"".join(f"3 {a} {b} {c}\n".encode() for a, b, c in tris)))
for e, name in (("<", "binary_little_endian"), (">", "binary_big_endian")):
    body = b"".join(struct.pack(e + "3f3B", *p, 1, 2, 3) for p in points)
    body += b"".join(struct.pack(e + "B3i", 3, *t) for t in tris)
    write("ply", name + ".ply", ply(name, body))
write("ply", "quad_normals.ply", b"ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
      b"property double z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\n"
      b"property list uchar uint vertex_index\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3\n")


# depth PNG + json
def png16(w, h, values):
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    rows = b"".join(b"\x00" + struct.pack(f">{w}H", *values[y * w:(y + 1) * w]) for y in range(h))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


depth = png16(8, 6, [0 if (i % 7 == 0) else 800 + i for i in range(48)])
cam = {"fx": 525.0, "fy": 525.0, "cx": 3.5, "cy": 2.5, "width": 8, "height": 6, "depth_scale": 1.0}
scene_cam = {"0": {"cam_K": [525.0, 0, 3.5, 0, 525.0, 2.5, 0, 0, 1], "depth_scale": 0.1}}
gt = {"0": [{"cam_R_m2c": [1, 0, 0, 0, 1, 0, 0, 0, 1], "cam_t_m2c": [0, 0, 800], "obj_id": 1}]}
gt_info = {"0": [{"bbox_obj": [1, 1, 3, 3], "bbox_visib": [1, 1, 3, 3], "px_count_all": 9,
                  "px_count_valid": 9, "px_count_visib": 9, "visib_fract": 1.0}]}
models = {"1": {"diameter": 172.0, "min_x": -50, "min_y": -50, "min_z": -70, "size_x": 100, "size_y": 100,
                "size_z": 140, "symmetries_discrete": [[-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]],
                "symmetries_continuous": [{"axis": [0, 0, 1], "offset": [0, 0, 0]}]}}
results = ("scene_id,im_id,obj_id,score,R,t,time\n1,0,1,0.9,1 0 0 0 1 0 0 0 1,0 0 800,0.01\n")
targets = [{"scene_id": 0, "im_id": 0, "obj_id": 1, "inst_count": 1}, {"scene_id": 0, "im_id": 0, "obj_id": 2, "inst_count": 2}]
for kind, doc in enumerate([cam, scene_cam, gt, gt_info, models, results, targets]):
    text = (doc if isinstance(doc, str) else json.dumps(doc)).encode()
    write("depth_png_json", f"kind{kind}", bytes([kind]) + struct.pack("<H", len(text)) + text + depth)


# view database (fuzz_view_database): the first byte even = a payload the target wraps in a valid
# header and checksum, odd = a whole file as written (header checks and the checksum itself).
def vpdb_payload(objects, views, grid_cell_m=0.003, cells=()):
    def s(text):
        b = text.encode()
        return struct.pack("<I", len(b)) + b

    def pts(ps):
        return struct.pack("<I", len(ps)) + b"".join(struct.pack("<3f", *p) for p in ps)

    params = {"camera": {"fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5, "width": 640, "height": 480},
              "subdivisions": 1, "distance_m": 1.0, "voxel_m": 0.003, "icp_voxel_m": 0.005, "normal_radius_m": 0.015,
              "drawn_mesh_error_m": 0.002, "grid_cell_m": grid_cell_m, "grid_margin_m": 0.04, "max_grid_bytes": 268435456,
              "ppf": {"sample_fraction": 0.5, "angle_bins": 4, "normal_split_deg": 30.0}, "max_pair_table_bytes": 268435456,
              "vfh": {"normalize_bins": True, "normalize_distances": False, "size_component": True, "pcl_compatible": True}}
    out = s(json.dumps(params, separators=(",", ":"))) + struct.pack("<I", len(objects))
    for oid, name, verts, tris, model in objects:
        out += struct.pack("<i", oid) + s(name) + struct.pack("<d", 0.1) + pts(verts)
        out += struct.pack("<I", len(tris)) + b"".join(struct.pack("<3I", *t) for t in tris)
        out += pts(model) + pts([(0.0, 0.0, 1.0)] * len(model))
        out += struct.pack("<I", 1) + struct.pack("<12d", -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 0)  # a half turn about z
        out += struct.pack("<I", 1) + struct.pack("<6d", 0, 0, 0, 0, 1, 0)  # axis z through the origin (interleaved)
        out += pts(verts) + struct.pack("<I", len(tris)) + b"".join(struct.pack("<3I", *t) for t in tris)  # drawing mesh
        out += struct.pack("<Q", len(cells)) + b"".join(struct.pack("<I", c) for c in cells)  # the ICP grid (none: filled later)
    out += struct.pack("<I", len(views))
    for obj, view_points in views:
        out += struct.pack("<I", obj) + struct.pack("<12d", 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.5)
        out += struct.pack("<308f", *[(i % 45) / 45.0 for i in range(308)])
        out += struct.pack("<90f", *[1.0 / (1 + i) for i in range(90)])
        out += struct.pack("<3f", 0.0, 0.0, 0.5)
        out += struct.pack("<I", len(view_points)) + pts(view_points[:2])
    return out


square = [(0.0, 0.0, 0.0), (0.1, 0.0, 0.0), (0.1, 0.1, 0.0), (0.0, 0.1, 0.0)]
payload = vpdb_payload([(1, "square", square, [(0, 1, 2), (0, 2, 3)], square)], [(0, square), (0, square[:3])])
write("view_database", "square_payload", b"\x00" + payload)
header = (b"VPDB\r\n\x1a\n" + struct.pack("<IIQI", 4, 0x01020304, len(payload), zlib.crc32(payload)) + b"\x00" * 4)
no_tables = struct.pack("<QII", 0, 0, 0)  # the pair tables' header: none stored (the CRC-32 of nothing is 0)
write("view_database", "square_file", b"\x01" + header + payload + no_tables)
write("view_database", "empty_payload", b"\x00" + vpdb_payload([], []))
# With a stored ICP grid: 5 cm cells over the square and a 4 cm margin are 4 x 4 x 2 cells, each
# holding one of its four points (index + 1).
write("view_database", "grid_payload", b"\x00" + vpdb_payload([(1, "square", square, [(0, 1, 2), (0, 2, 3)], square)],
                                                               [(0, square)], grid_cell_m=0.05, cells=[1 + k % 4 for k in range(32)]))
# With a stored pair table, in the shape the parameters above give (sample fraction 0.5: 3 distance
# bins; 4 angle bins: 2 feature angle bins; 3 * 2^3 keys): two points, and the pair each way, by key.
def u32s(values):
    return struct.pack("<Q", len(values)) + b"".join(struct.pack("<I", v) for v in values)


key_start = [0] * 5 + [2] * 20  # keys 0-3 empty, key 4 holds both pairs
table = (b"\x01" + struct.pack("<ddid", 0.1, 0.5, 4, 30.0) + struct.pack("<I", 2) + struct.pack("<6f", 0, 0, 0, 0.05, 0, 0)
         + struct.pack("<I", 2) + struct.pack("<6f", 0, 0, 1, 0, 0, 1) + u32s(key_start) + u32s([(0 << 14) | 100, (1 << 14) | 7000]))
# (First byte 2: the next four bytes are the payload's length, the pair tables follow it.)
table_db = vpdb_payload([(1, "square", square, [(0, 1, 2), (0, 2, 3)], square)], [(0, square)])
write("view_database", "pair_table_payload", b"\x02" + struct.pack("<I", len(table_db)) + table_db + table)
