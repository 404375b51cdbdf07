#!/usr/bin/python3
"""Junctions of known angle (issue 64): two planar sheets crossing (X) or ending on one
another (T) at 15, 30, 60 and 90 degrees, the junction line of random direction (seeds),
meshed at r = 2 ... 15 by each surface method; per run the junction as the mesh has it.

    /usr/bin/python3 bench/junction_sweep.py BUILD [--angles 15,30,60,90] [--kinds x,t]
        [--seeds 1,2,3] [--rs 2,4,7,11,15] [--methods scvd,midsurface] [--dims 96]
        [--volume_mesh] [--extract] [--flags "--plc_junction_voxels=0 ..."] [--tag T]

Per run: S (formula 5), triangles, pieces per plane, the junction's edges (edges between
faces of different pieces, or of three or more faces), the largest distance of their
vertices from the true line (voxels), the narrowest and widest dihedral across them (the
wedge between the two sheets' faces meeting there, against the true angle), and with
--volume_mesh the PLC's narrowest wedge and the mesh's smallest angle, beside the narrowest
wedge of the truth (the junction's angle, and each sheet against each box face it reaches:
an input wedge can be no wider than the rock's).
"""
import argparse
import json
import math
import pathlib
import subprocess
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent
OUT = ROOT / "out" / "junctions"


def read_ply(path):
    """(vertices (n,3), faces (m,3), face piece (m,)) of an ascii PLY written by sheetmesh."""
    with open(path) as f:
        header = []
        while True:
            line = f.readline().strip()
            header.append(line)
            if line == "end_header":
                break
        nv = int(next(l.split()[2] for l in header if l.startswith("element vertex")))
        nf = int(next(l.split()[2] for l in header if l.startswith("element face")))
        face_props = []
        in_face = False
        for l in header:
            if l.startswith("element face"):
                in_face = True
            elif l.startswith("element"):
                in_face = False
            elif in_face and l.startswith("property") and "list" not in l:
                face_props.append(l.split()[-1])
        verts = np.array([[float(x) for x in f.readline().split()[:3]] for _ in range(nv)])
        faces, pieces = [], []
        for _ in range(nf):
            parts = f.readline().split()
            k = int(parts[0])
            faces.append([int(x) for x in parts[1:1 + k]])
            rest = parts[1 + k:]
            pieces.append(int(float(rest[face_props.index("piece")])) if "piece" in face_props else 0)
    return verts, np.array(faces), np.array(pieces)


def dihedral(a, b, c, d):
    """Angle (degrees) between the half-planes (a, b, c) and (a, b, d) about edge ab."""
    e = b - a
    e = e / np.linalg.norm(e)
    u = (c - a) - e * np.dot(c - a, e)
    v = (d - a) - e * np.dot(d - a, e)
    cu = np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v) + 1e-30)
    return math.degrees(math.acos(max(-1, min(1, cu))))


def junction_figures(ply, truth):
    verts, faces, pieces = read_ply(ply)
    edges = {}
    for f, t in enumerate(faces):
        for k in range(3):
            a, b = sorted((t[k], t[(k + 1) % 3]))
            edges.setdefault((a, b), []).append(f)
    junction = [(e, fs) for e, fs in edges.items()
                if len(fs) >= 3 or (len(fs) == 2 and pieces[fs[0]] != pieces[fs[1]])]
    j = truth["junctions"][0]
    p, u = np.array(j["point"]), np.array(j["direction"])
    dist, angles = 0.0, []
    for (a, b), fs in junction:
        for v in (a, b):
            w = verts[v] - p
            dist = max(dist, float(np.linalg.norm(w - u * np.dot(w, u))))
        for x in range(len(fs)):
            for y in range(x + 1, len(fs)):
                if pieces[fs[x]] == pieces[fs[y]]:
                    continue
                c = [q for q in faces[fs[x]] if q not in (a, b)][0]
                d = [q for q in faces[fs[y]] if q not in (a, b)][0]
                angles.append(dihedral(verts[a], verts[b], verts[c], verts[d]))
    # Pieces per plane: each piece's mean face normal against the two sheets' normals.
    normals = [np.array(s["normal"]) for s in truth["sheets"]]
    per_plane = [set(), set()]
    for piece in set(pieces.tolist()):
        sel = faces[pieces == piece]
        n = np.zeros(3)
        for t in sel:
            m = np.cross(verts[t[1]] - verts[t[0]], verts[t[2]] - verts[t[0]])
            if np.dot(m, n) < 0:
                m = -m
            n += m
        n /= np.linalg.norm(n) + 1e-30
        k = int(np.argmax([abs(np.dot(n, q)) for q in normals]))
        per_plane[k].add(piece)
    return {
        "junction_edges": len(junction),
        "junction_distance": round(dist, 3),
        "wedge_min": round(min(angles), 2) if angles else None,
        "wedge_max": round(max(angles), 2) if angles else None,
        "pieces_per_plane": [len(s) for s in per_plane],
    }


def true_wedge(vol, truth):
    """The narrowest wedge the rock itself has: the junction's angle, and for each sheet
    and each box face it reaches, the angle between the sheet's plane and the face's."""
    dims = truth["dims"]
    img = np.fromfile(vol, dtype=np.uint8).reshape(dims[2], dims[1], dims[0])
    j = truth["junctions"][0]
    narrowest = min(j["degrees"], 180 - j["degrees"])
    for s in truth["sheets"]:
        n, c = np.array(s["normal"]), np.array(s["center"])
        half = s["aperture"]["max"] / 2 + 1.0
        others = [np.array(o["normal"]) for o in truth["sheets"] if o is not s]
        for k in range(3):
            for side in (0, dims[k] - 1):
                layer = np.take(img, side, axis=2 - k)
                zs, ys = np.nonzero(layer)  # the face's sheet voxels (row, column)
                if not len(zs):
                    continue
                idx = [None, None, None]
                rest = [a for a in range(3) if a != k]
                idx[rest[1]], idx[rest[0]] = zs, ys
                idx[k] = np.full(len(zs), side)
                pts = np.stack(idx, axis=1).astype(float)
                d = np.abs((pts - c) @ n)
                # Voxels of this sheet, away from where the other sheets pass.
                mine = d <= half
                for o, other in zip(others, [x for x in truth["sheets"] if x is not s]):
                    mine &= np.abs((pts - np.array(other["center"])) @ o) > other["aperture"]["max"] / 2 + 2
                if mine.sum() >= 3:
                    narrowest = min(narrowest, math.degrees(math.acos(min(1.0, abs(n[k])))))
    return round(narrowest, 2)


def run(build, folder, angle, kind, seed, r, method, dims, volume_mesh, extract, flags=(), tag=""):
    cli = str(pathlib.Path(build) / "worker" / "pipeline" / "sheetmesh-pipeline")
    vol = folder / ("j%d%s_s%d_%dx%dx%d_u8.raw" % (angle, kind, seed, dims, dims, dims))
    if not vol.exists():
        subprocess.run([cli, "phantom", "--preset=crossing", "--dims=%dx%dx%d" % (dims, dims, dims),
                        "--junction_degrees=%d" % angle, "--junction=" + kind, "--seed=%d" % seed,
                        "-o", str(vol)], check=True, stdout=subprocess.DEVNULL)
    truth = json.loads(pathlib.Path(str(vol) + ".truth.json").read_text())
    out = folder / ("out_%d%s_s%d_r%g_%s%s%s" % (angle, kind, seed, r, method,
                                                 "_extract" if extract else "",
                                                 "_" + tag if tag else ""))
    cmd = [cli, "run" if extract else "surface", str(vol), "-o", str(out), "--r=%g" % r,
           "--surface_mesher=" + method, "--surface_representation=sheet",
           "--similarity_hausdorff=false"]
    if volume_mesh:
        cmd.append("--volume_mesh")
    cmd += list(flags)
    p = subprocess.run(cmd, capture_output=True, text=True)
    row = {"angle": angle, "kind": kind, "seed": seed, "r": r, "method": method}
    if p.returncode != 0:
        row["error"] = p.stderr.strip().splitlines()[-1][:160]
        return row
    report = json.loads((out / "report.json").read_text())
    row["similarity"] = round(report["similarity"]["similarity"], 4)
    row["triangles"] = report["surface"]["triangles"]
    row.update(junction_figures(out / "surface.ply", truth))
    row["true_wedge"] = true_wedge(vol, truth)
    if volume_mesh and "volume_mesh" in report:
        v = report["volume_mesh"]
        row["plc_wedge"] = round(v["input_wedges"]["narrowest_degrees"], 2)
        row["min_dihedral"] = round(v["quality"]["min_dihedral_degrees"]["min"], 2)
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--angles", default="15,30,60,90")
    ap.add_argument("--kinds", default="x,t")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--rs", default="2,4,7,11,15")
    ap.add_argument("--methods", default="scvd,midsurface")
    ap.add_argument("--dims", type=int, default=96)
    ap.add_argument("--volume_mesh", action="store_true")
    ap.add_argument("--extract", action="store_true", help="run (extraction) rather than surface")
    ap.add_argument("--flags", default="", help="more flags for every run, space-separated")
    ap.add_argument("--tag", default="", help="appended to each run's output folder")
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    for angle in [int(a) for a in args.angles.split(",")]:
        for kind in args.kinds.split(","):
            for seed in [int(s) for s in args.seeds.split(",")]:
                for r in [float(x) for x in args.rs.split(",")]:
                    for method in args.methods.split(","):
                        row = run(args.build, OUT, angle, kind, seed, r, method, args.dims,
                                  args.volume_mesh, args.extract, args.flags.split(), args.tag)
                        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
