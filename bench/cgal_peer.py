#!/usr/bin/python3
"""The volume mesh against CGAL Mesh_3 on the labelled image, per tetrahedron.

What a user would run instead of sheetmesh: CGAL Mesh_3 (Debian's python3-pygalmesh,
`generate_from_array`) on the image labelled rock = 1 and fracture = 2, so that the fracture
is a subdomain of the box. Its similarity is formula 5 on the voxels whose centres lie in
its fracture tetrahedra (C_in of them sheet voxels, C_out not, over the sheet voxels). It
runs at several sizes (max_cell_circumradius and max_facet_distance), ours at several r
(`surface --volume_mesh`, the report's similarity); each gives S against tetrahedra, with
the minimum dihedral angle beside it. One PNG per volume: S against tetrahedra, both.

Usage: /usr/bin/python3 bench/cgal_peer.py [BUILD_DIR] [--only NAME] [--r 3,4,5,7,11]
    [--sizes 2,3,4,6,9]
Writes bench/out/cgal_peer.md and bench/out/cgal_peer_NAME.png.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fidelity  # noqa: E402
from volume_mesh import quality  # noqa: E402  (per-tetrahedron dihedral angles)

ROOT = fidelity.ROOT


def load(raw, dims, value):
    nx, ny, nz = dims
    v = np.fromfile(raw, dtype=np.uint8, count=nx * ny * nz).reshape(nz, ny, nx)
    return v == value


def fracture_voxels_in(points, tets, shape):
    """The voxels (z, y, x) whose centres lie in one of the tetrahedra (points in x, y, z
    voxel coordinates, centres at integers)."""
    inside = np.zeros(shape, dtype=bool)
    for t in tets:
        p = points[t]
        lo = np.maximum(np.floor(p.min(axis=0)).astype(int), 0)
        hi = np.minimum(np.ceil(p.max(axis=0)).astype(int), np.array(shape[::-1]) - 1)
        if np.any(hi < lo):
            continue
        xs, ys, zs = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1),
                                 np.arange(lo[2], hi[2] + 1), indexing="ij")
        q = np.stack([xs.ravel(), ys.ravel(), zs.ravel()], axis=1).astype(float)
        m = np.column_stack([p[1] - p[0], p[2] - p[0], p[3] - p[0]])
        try:
            lam = np.linalg.solve(m, (q - p[0]).T).T
        except np.linalg.LinAlgError:
            continue
        ok = (lam >= -1e-9).all(axis=1) & (lam.sum(axis=1) <= 1 + 1e-9)
        sel = q[ok].astype(int)
        inside[sel[:, 2], sel[:, 1], sel[:, 0]] = True
    return inside


def cgal(mask, size):
    import pygalmesh
    labels = np.where(mask, 2, 1).astype(np.uint8)
    # pygalmesh takes the array (x, y, z); the mesh comes in voxel units from the corner.
    vol = np.ascontiguousarray(labels.transpose(2, 1, 0))
    t0 = time.perf_counter()
    m = pygalmesh.generate_from_array(vol, (1.0, 1.0, 1.0), max_cell_circumradius=float(size),
                                      max_facet_distance=0.5 * size ** 0.5, verbose=False, seed=1)
    seconds = time.perf_counter() - t0
    tets = m.get_cells_type("tetra")
    sub = None
    for key in ("medit:ref", "cell_data"):
        if key in m.cell_data:
            sub = np.asarray(m.cell_data[key][[c.type for c in m.cells].index("tetra")])
    points = m.points - 0.5  # voxel centres at integers
    frac = tets[sub == 2] if sub is not None else tets[:0]
    inside = fracture_voxels_in(points, frac, mask.shape)
    c_in = int((inside & mask).sum())
    c_out = int((inside & ~mask).sum())
    s = (c_in - c_out) / max(1, int(mask.sum()))
    q, _ = quality(points, tets)
    return {"tets": len(tets), "S": s, "min": float(q.min()), "mean": float(q.mean()), "seconds": seconds}


def ours(cli, raw, dims, value, r, out_dir):
    d = os.path.join(out_dir, "ours_r%g" % r)
    t0 = time.perf_counter()
    res = subprocess.run([cli, "surface", raw, "--labels=%g" % value, "--r=%g" % r, "-o", d, "--volume_mesh",
                          "--output_formats=ply", "--output_volume_formats=vtu", "--similarity_hausdorff=false",
                          "--similarity_grid_rates="] + fidelity.dims_flag(raw, dims), capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if res.returncode != 0:
        return {"error": res.stderr.strip().splitlines()[-1][:100]}
    rep = json.load(open(os.path.join(d, "report.json")))
    vm = rep["volume_mesh"]
    q = vm["quality"]["min_dihedral_degrees"]
    return {"tets": vm["tetrahedra"], "S": rep["similarity"]["similarity"], "min": q["min"], "mean": q["mean"],
            "seconds": seconds}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=os.path.join(ROOT, "build"))
    ap.add_argument("--only", default="")
    ap.add_argument("--r", default="3,4,5,7,11")
    ap.add_argument("--sizes", default="2,3,4,6,9")
    a = ap.parse_args()
    cli = os.path.join(a.build, "worker", "pipeline", "sheetmesh-pipeline")
    out = os.path.join(ROOT, "bench", "out")
    vols = fidelity.volumes(cli, out)
    if a.only:
        vols = [v for v in vols if any(k in v[0] for k in a.only.split(","))]
    lines = ["| volume | mesher | setting | tetrahedra | S | min° | mean° | seconds |", "|---|---|---|---|---|---|---|---|"]
    for name, raw, dims, value in vols:
        work = os.path.join(out, "cgal_peer", name.replace(" ", "_").replace("^", ""))
        os.makedirs(work, exist_ok=True)
        mask = load(raw, dims, value)
        rows = []
        for r in [float(x) for x in a.r.split(",")]:
            row = ours(cli, raw, dims, value, r, work)
            rows.append(("sheetmesh", "r %g" % r, row))
        for size in [float(x) for x in a.sizes.split(",")]:
            rows.append(("CGAL Mesh_3", "size %g" % size, cgal(mask, size)))
        for who, setting, row in rows:
            if "error" in row:
                lines.append("| %s | %s | %s | failed: %s | | | | |" % (name, who, setting, row["error"]))
            else:
                lines.append("| %s | %s | %s | %d | %.3f | %.2f | %.2f | %.1f |" % (
                    name, who, setting, row["tets"], row["S"], row["min"], row["mean"], row["seconds"]))
        print("\n".join(lines[-len(rows):]), flush=True)
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
            fig, ax = plt.subplots(figsize=(6, 4))
            for who, marker in (("sheetmesh", "o-"), ("CGAL Mesh_3", "s--")):
                pts = sorted((row["tets"], row["S"]) for w, _, row in rows if w == who and "error" not in row)
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], marker, label=who)
            ax.set_xscale("log")
            ax.set_xlabel("tetrahedra")
            ax.set_ylabel("similarity S (formula 5)")
            ax.set_title(name)
            ax.legend()
            fig.tight_layout()
            fig.savefig(os.path.join(out, "cgal_peer_%s.png" % name.replace(" ", "_").replace("^", "")), dpi=100)
            plt.close(fig)
        except ImportError:
            pass
    text = "\n".join(lines) + "\n"
    open(os.path.join(out, "cgal_peer.md"), "w").write(text)
    print(text)


if __name__ == "__main__":
    main()
