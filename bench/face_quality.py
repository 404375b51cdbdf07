#!/usr/bin/python3
"""What a simulation takes from each sheet triangle: its aperture, and how it lies.

For every benchmark volume (bench/fidelity.py's and bench/volume_mesh_sweep.py's presets)
and r in 3, 5, 8, `sheetmesh-pipeline run` (extraction, the defaults) writes surface.ply;
per run this counts, from the files alone:
- faces without aperture (the face property aperture_voxels; --field thickness_voxels
  measures the fitted prism heights instead), and of those the ones that pass through the
  sheet phase (the model the run scored against): those are not holes, and a flow model
  would close them;
- faces at a junction (a vertex on an edge three or more faces share): their aperture
  against the median of their own piece's faces away from junctions;
- tilt: each face's normal against its piece's plane (area-weighted least squares), the
  share over 30°, split by where the face lies (beside a junction, on a rim, inside).

Usage: /usr/bin/python3 bench/face_quality.py [BUILD_DIR] [--r 3,5,8] [--only NAME,...]
           [--field aperture_voxels|thickness_voxels] [--FLAG=VALUE for the runs]
Writes bench/out/face_quality.md and prints it.
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fidelity  # noqa: E402
import volume_mesh_sweep  # noqa: E402

ROOT = fidelity.ROOT
APERTURE = "aperture_voxels"  # --field thickness_voxels: the fitted prism heights instead


def read_ply(path):
    """Vertices (n, 3), faces (m, 3), face thickness in voxels (m), face piece (m) of an
    ASCII surface.ply as sheetmesh writes it."""
    with open(path) as f:
        props, counts, element = {"vertex": [], "face": []}, {}, None
        for line in f:
            w = line.split()
            if w[0] == "element":
                element = w[1]
                counts[element] = int(w[2])
            elif w[0] == "property" and element:
                props[element].append(w[-1])
            elif w[0] == "end_header":
                break
        nv, nf = counts["vertex"], counts["face"]
        verts = np.array([f.readline().split()[:3] for _ in range(nv)], dtype=float)
        faces, thick, piece, body = [], [], [], []
        fp = props["face"][1:]  # after the vertex list
        for _ in range(nf):
            w = f.readline().split()
            k = int(w[0])
            faces.append([int(x) for x in w[1:1 + k]])
            rest = dict(zip(fp, w[1 + k:]))
            thick.append(float(rest[APERTURE if APERTURE in rest else "thickness_voxels"]))
            piece.append(int(rest.get("piece", 0)))
            body.append(int(rest.get("body", 0)))
    keep = np.array(body) == 0  # bodies' faces are a closed surface: no aperture, no plane
    return verts, np.array(faces)[keep], np.array(thick)[keep], np.array(piece)[keep]


def passes_through(phase, tri):
    """Whether a triangle (3x3, voxel coordinates x, y, z) passes within half a voxel of a
    voxel of `phase` (z, y, x): sampled every half voxel."""
    a, b, c = tri
    n = max(2, int(np.ceil(2 * max(np.linalg.norm(b - a), np.linalg.norm(c - a), np.linalg.norm(c - b)))))
    for i in range(n + 1):
        for j in range(n + 1 - i):
            p = a + (b - a) * i / n + (c - a) * j / n
            x, y, z = np.rint(p).astype(int)
            if 0 <= z < phase.shape[0] and 0 <= y < phase.shape[1] and 0 <= x < phase.shape[2] and phase[z, y, x]:
                return True
    return False


def measure(out_dir, raw, dims, value):
    report = json.load(open(os.path.join(out_dir, "report.json")))
    placement = report["input"]
    verts, faces, thick, piece = read_ply(os.path.join(out_dir, "surface.ply"))
    if len(faces) == 0:
        return None
    # Back to voxel coordinates.
    verts = (verts - np.array(placement["origin"])) / np.array(placement["spacing"])
    labels = [f for f in os.listdir(out_dir) if f.startswith("model_labels_")]
    if labels:
        phase = np.fromfile(os.path.join(out_dir, labels[0]), dtype=np.uint16).reshape(dims[::-1]) > 0
    else:
        phase = np.fromfile(raw, dtype=np.uint8).reshape(dims[::-1]) == value
    tri = verts[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * np.linalg.norm(normal, axis=1)
    unit = normal / np.maximum(2 * area, 1e-12)[:, None]
    # Edges and the faces that share them.
    edge_faces = {}
    for f, t in enumerate(faces):
        for k in range(3):
            e = (min(t[k], t[(k + 1) % 3]), max(t[k], t[(k + 1) % 3]))
            edge_faces.setdefault(e, []).append(f)
    junction_vertex = np.zeros(len(verts), bool)
    rim_vertex = np.zeros(len(verts), bool)
    for (a, b), fs in edge_faces.items():
        if len(fs) >= 3:
            junction_vertex[[a, b]] = True
        elif len(fs) == 1:
            rim_vertex[[a, b]] = True
    at_junction = junction_vertex[faces].any(axis=1)
    on_rim = rim_vertex[faces].any(axis=1) & ~at_junction
    zero = thick <= 0
    zero_through = sum(passes_through(phase, tri[f]) for f in np.flatnonzero(zero))
    ratios, tilt = [], np.zeros(len(faces))
    for p in np.unique(piece):
        mine = piece == p
        away = mine & ~at_junction & ~zero
        if away.any():
            ref = np.median(thick[away])
            ratios += list(thick[mine & at_junction & ~zero] / ref)
        w = area[mine]
        c = (tri[mine].mean(axis=1) * w[:, None]).sum(axis=0) / max(w.sum(), 1e-12)
        d = tri[mine].mean(axis=1) - c
        _, vecs = np.linalg.eigh((d * w[:, None]).T @ d)
        plane_normal = vecs[:, 0]
        tilt[mine] = np.degrees(np.arccos(np.clip(np.abs(unit[mine] @ plane_normal), 0, 1)))
    steep = tilt > 30
    inside = ~at_junction & ~on_rim
    return {
        "faces": len(faces), "pieces": len(np.unique(piece)), "zero": int(zero.sum()),
        "zero_through": int(zero_through), "junction_faces": int(at_junction.sum()),
        "junction_ratio_median": float(np.median(ratios)) if ratios else float("nan"),
        "junction_ratio_p90": float(np.percentile(ratios, 90)) if ratios else float("nan"),
        "steep": float(steep.mean()),
        "steep_junction": int((steep & at_junction).sum()), "steep_rim": int((steep & on_rim).sum()),
        "steep_inside": int((steep & inside).sum()),
        "steep_inside_share": float((steep & inside).sum() / max(inside.sum(), 1)),
        "similarity": report["similarity"]["similarity"],
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=os.path.join(ROOT, "build"))
    ap.add_argument("--r", default="3,5,8")
    ap.add_argument("--only", default="")
    ap.add_argument("--field", default="aperture_voxels", help="the face property measured")
    args, extra = ap.parse_known_args()
    global APERTURE
    APERTURE = args.field
    cli = os.path.join(args.build, "worker", "pipeline", "sheetmesh-pipeline")
    out_dir = os.path.join(ROOT, "bench", "out", "face_quality")
    os.makedirs(out_dir, exist_ok=True)
    vols = fidelity.volumes(cli, os.path.join(ROOT, "bench", "out")) + \
        volume_mesh_sweep.preset_volumes(cli, os.path.join(ROOT, "bench", "out", "volume_mesh_sweep"))
    only = [s.strip().lower() for s in args.only.split(",") if s.strip()]
    rows = []
    for name, raw, dims, value in vols:
        if only and not any(o in name.lower() for o in only):
            continue
        for r in [float(x) for x in args.r.split(",")]:
            d = os.path.join(out_dir, "%s_r%g" % (name.replace(" ", "_").replace("^", ""), r))
            subprocess.run([cli, "run", raw, "-o", d, "--labels=%g" % value, "--r=%g" % r,
                            "--output_formats=ply", "--output_previews=false", "--similarity_grid_rates=",
                            "--output_label_volume=raw"]
                           + fidelity.dims_flag(raw, dims) + extra, check=True, capture_output=True)
            m = measure(d, raw, dims, value)
            if m is None:
                print("%s r = %g: every piece a body, no sheet" % (name, r), file=sys.stderr)
                continue
            rows.append((name, r, m))
            print(name, r, m, file=sys.stderr)
    lines = ["%s per face\n" % args.field, "| volume | r | faces | pieces | S | zero (over the phase) | junction faces | "
             "junction / own piece (median, p90) | tilted > 30° | of them: junction, rim, inside | "
             "inside faces tilted |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, r, m in rows:
        lines.append("| %s | %g | %d | %d | %.3f | %d (%d) | %d | %.2f, %.2f | %.1f%% | %d, %d, %d | %.1f%% |" % (
            name, r, m["faces"], m["pieces"], m["similarity"], m["zero"], m["zero_through"], m["junction_faces"],
            m["junction_ratio_median"], m["junction_ratio_p90"], 100 * m["steep"], m["steep_junction"],
            m["steep_rim"], m["steep_inside"], 100 * m["steep_inside_share"]))
    text = "\n".join(lines) + "\n"
    open(os.path.join(ROOT, "bench", "out", "face_quality.md"), "w").write(text)
    print(text)


if __name__ == "__main__":
    main()
