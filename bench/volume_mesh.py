#!/usr/bin/python3
"""Volume mesh: node and tet counts, Table 3 quality and wall time, against a peer.

sheetmesh: `surface --volume_mesh` at r with its defaults (the one-layer sheets as internal
facets of the box, TetGen adding no points on them). Peer: marching cubes (scikit-image) of
the sheet phase, decimated with VTK's quadric decimation to the fewest triangles (from a
ladder of multiples of sheetmesh's count) whose enclosed volume scores at least sheetmesh's
similarity; that closed surface goes into a box one voxel larger on every side and TetGen
meshes it with the same quality bound (`-pzQq1.5/10O2/3`, free to refine its facets). Both
are scored by sheetmesh's scorer; the peer's tet quality is computed here with the same
formulas (ALGORITHM §11).

The volume-stage seconds stand beside TetGen's own on the same PLC (the report's
tetgen_seconds), and the peak RSS of the whole run is read with /usr/bin/time -v. With
--paper the paper-scale phantom (1012 x 1024 x 931, `phantom --preset=paper`) is added at
r = 15, the radius the paper meshed its rock at; the peer is not run there (marching cubes of
1e9 voxels does not fit the benchmark's budget).

Usage: /usr/bin/python3 bench/volume_mesh.py [BUILD_DIR] [--r 7] [--paper] [--only NAME]
    [--flags "--plc_lattice=0" --tag NAME]
Writes bench/out/volume_mesh.md and prints the table. With --flags (extra sheetmesh-pipeline
flags, e.g. the 0.3 defaults "--plc_lattice=0 --tet_steiner_on_sheets=true"), the peer (which does not
depend on them) is left out and the table goes to bench/out/volume_mesh_NAME.md.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fidelity  # noqa: E402  (marching cubes + decimation peer, benchmark volumes)

ROOT = fidelity.ROOT


PEER_SWITCHES = "-pzQq1.5/10O2/3"


def ours(cli, raw, value, r, out_dir, flags=(), tag=""):
    """The run's report, wall seconds and peak RSS (MiB)."""
    d = os.path.join(out_dir, "ours_vol_r%g%s" % (r, "_" + tag if tag else ""))
    t = time.perf_counter()
    res = subprocess.run(["/usr/bin/time", "-v", cli, "surface", raw, "--labels=%g" % value, "--r=%g" % r,
                          "-o", d, "--output_formats=ply", "--similarity_hausdorff=false",
                          "--similarity_grid_rates=", "--volume_mesh", "--output_volume_formats=vtu"]
                         + list(flags), capture_output=True, text=True)
    wall = time.perf_counter() - t
    if res.returncode != 0:
        raise subprocess.CalledProcessError(res.returncode, res.args, res.stdout, res.stderr)
    rss = 0.0
    for line in res.stderr.splitlines():
        if "Maximum resident set size" in line:
            rss = int(line.split(":")[1]) / 1024.0
    rep = json.load(open(os.path.join(d, "report.json")))
    return rep, wall, rss


def read_ply_triangles(path):
    """Vertices and triangles of a PLY written by VTK (binary little-endian or ASCII)."""
    import vtk
    from vtk.util import numpy_support
    reader = vtk.vtkPLYReader()
    reader.SetFileName(path)
    reader.Update()
    poly = reader.GetOutput()
    pts = numpy_support.vtk_to_numpy(poly.GetPoints().GetData()).astype(np.float64)
    conn = numpy_support.vtk_to_numpy(poly.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    # Merge coincident points and drop triangles that collapsed or have no area: TetGen
    # aborts on such input, and any user of the peer would clean it first.
    uniq, inverse = np.unique(np.round(pts, 9), axis=0, return_inverse=True)
    conn = inverse.reshape(-1)[conn]
    p = uniq[conn]
    area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    keep = (conn[:, 0] != conn[:, 1]) & (conn[:, 1] != conn[:, 2]) & (conn[:, 0] != conn[:, 2]) & (area > 1e-9)
    return uniq, conn[keep]


def write_poly(path, pts, tris, dims, margin):
    nx, ny, nz = dims
    lo = np.array([-0.5 - margin] * 3)
    hi = np.array([nx - 0.5 + margin, ny - 0.5 + margin, nz - 0.5 + margin])
    corners = np.array([[hi[0] if c & 1 else lo[0], hi[1] if c & 2 else lo[1], hi[2] if c & 4 else lo[2]]
                        for c in range(8)])
    allp = np.vstack([corners, pts])
    with open(path, "w") as f:
        f.write("%d 3 0 0\n" % len(allp))
        for i, p in enumerate(allp):
            f.write("%d %.17g %.17g %.17g\n" % (i, p[0], p[1], p[2]))
        box = [[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4], [2, 3, 7, 6], [0, 2, 6, 4], [1, 3, 7, 5]]
        f.write("%d 1\n" % (len(box) + len(tris)))
        for q in box:
            f.write("1 0 1\n4 %d %d %d %d\n" % tuple(q))
        for t in tris:
            f.write("1 0 2\n3 %d %d %d\n" % (t[0] + 8, t[1] + 8, t[2] + 8))
        f.write("0\n0\n")


def load_tetgen(base):
    nodes = np.loadtxt(base + ".node", skiprows=1, comments="#", ndmin=2)[:, 1:4]
    tets = np.loadtxt(base + ".ele", skiprows=1, comments="#", dtype=np.int64, ndmin=2)[:, 1:5]
    return nodes, tets


def quality(nodes, tets):
    """Per-tet minimum dihedral angle (degrees) and radius aspect 3 r_in / R_circ."""
    p = nodes[tets]
    dmin = np.full(len(tets), 180.0)
    for i, j in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]:
        k, l = [x for x in range(4) if x not in (i, j)]
        e = p[:, j] - p[:, i]
        n1 = np.cross(e, p[:, k] - p[:, i])
        n2 = np.cross(e, p[:, l] - p[:, i])
        c = np.sum(n1 * n2, 1) / (np.linalg.norm(n1, axis=1) * np.linalg.norm(n2, axis=1) + 1e-300)
        dmin = np.minimum(dmin, np.degrees(np.arccos(np.clip(c, -1, 1))))
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    vol6 = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    areas = sum(0.5 * np.linalg.norm(np.cross(p[:, y] - p[:, x], p[:, z] - p[:, x]), axis=1)
                for x, y, z in [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)])
    r_in = 0.5 * vol6 / (areas + 1e-300)
    num = (np.sum(a * a, 1)[:, None] * np.cross(b, c) + np.sum(b * b, 1)[:, None] * np.cross(c, a)
           + np.sum(c * c, 1)[:, None] * np.cross(a, b))
    r_circ = np.linalg.norm(num, axis=1) / (2 * vol6 + 1e-300)
    return dmin, 3 * r_in / (r_circ + 1e-300)


def peer(cli, raw, dims, value, start, target, switches, out_dir):
    """The fewest decimated marching-cubes triangles reaching `target` that TetGen accepts."""
    tried = []
    for mult in [0.25, 0.35, 0.5, 0.7, 1, 1.5, 2, 3, 4, 6, 8, 12, 16, 24, 32]:
        tri, sim, _, _, full, _ = fidelity.peer(cli, raw, dims, value, int(start * mult), out_dir)
        if sim < target and tri < full:
            continue
        path = os.path.join(out_dir, "peer_%d.ply" % int(start * mult))
        pts, tris = read_ply_triangles(path)
        poly = os.path.join(out_dir, "peer_tet.poly")
        write_poly(poly, pts, tris, dims, 1.0)
        for old in [poly[:-5] + ".1." + ext for ext in ("node", "ele", "face", "edge")]:
            if os.path.exists(old):
                os.remove(old)
        t = time.perf_counter()
        res = subprocess.run(["tetgen"] + switches.split() + [poly], capture_output=True, text=True, timeout=1800)
        wall = time.perf_counter() - t
        if res.returncode != 0 or not os.path.exists(poly[:-5] + ".1.ele"):
            tried.append("%d triangles: TetGen failed (%s)" % (
                tri, " ".join((res.stdout + res.stderr).strip().splitlines()[-1:])))
            if len(tried) >= 4 or tri >= full:
                break
            continue
        nodes, tets = load_tetgen(poly[:-5] + ".1")
        dmin, rasp = quality(nodes, tets)
        return dict(triangles=tri, similarity=sim, nodes=len(nodes), tets=len(tets), seconds=wall,
                    dmin_min=dmin.min(), dmin_mean=dmin.mean(), rasp_mean=rasp.mean(), failed=tried)
    return dict(error=tried)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=os.path.join(ROOT, "build"))
    ap.add_argument("--r", type=float, default=7)
    ap.add_argument("--flags", default="", help="extra sheetmesh-pipeline flags (peer left out)")
    ap.add_argument("--tag", default="variant", help="names the output table with --flags")
    ap.add_argument("--paper", action="store_true", help="add the paper-scale phantom at r = 15")
    ap.add_argument("--only", default="", help="only the volumes whose name contains this")
    args = ap.parse_args()
    cli = os.path.join(args.build, "worker", "pipeline", "sheetmesh-pipeline")
    out_root = os.path.join(ROOT, "bench", "out", "fidelity")
    os.makedirs(out_root, exist_ok=True)
    lines = ["| volume | voxels | sheetmesh: triangles, similarity | nodes | tets (voxels per tet) | "
             "min dihedral min / mean | gamma mean | radius aspect mean | edge aspect mean | "
             "volume stage s / TetGen s / total s | peak RSS MiB | "
             "peer: triangles, similarity | peer nodes | peer tets | peer min dihedral min / mean | "
             "peer radius aspect mean | peer TetGen s |",
             "|" + "---|" * 17]
    vols = [(name, raw, dims, value, args.r) for name, raw, dims, value in fidelity.volumes(cli, out_root)]
    if args.paper:
        raw = os.path.join(out_root, "paper_1012x1024x931_u8.raw")
        if not os.path.exists(raw):
            fidelity.run([cli, "phantom", "--preset=paper", "-o", raw])
        vols.append(("preset paper", raw, (1012, 1024, 931), 255, 15.0))
    for name, raw, dims, value, r in vols:
        if args.only and args.only not in name:
            continue
        vdir = os.path.join(out_root, name.replace(" ", "_").replace("^", ""))
        os.makedirs(vdir, exist_ok=True)
        try:
            rep, wall, rss = ours(cli, raw, value, r, vdir, args.flags.split(),
                                  args.tag if args.flags else "")
        except subprocess.CalledProcessError as e:
            line = "| %s | %d | volume stage failed: %s |" % (name, dims[0] * dims[1] * dims[2],
                                                           (e.stderr or "").strip().splitlines()[-1])
            print(line, flush=True)
            lines.append(line)
            continue
        vm, q = rep["volume_mesh"], rep["volume_mesh"]["quality"]
        sim = rep["similarity"]["similarity"]
        tri = rep["surface"]["triangles"]
        vox = dims[0] * dims[1] * dims[2]
        p = ({"error": ["not run (--flags)"]} if args.flags else
             {"error": ["not run at this scale"]} if name == "preset paper" else
             peer(cli, raw, dims, value, tri, sim, PEER_SWITCHES, vdir))
        if "error" in p:
            peer_cols = "%s | | | | |" % "; ".join(p["error"])
        else:
            peer_cols = "%d, %.4f%s | %d | %d | %.2f° / %.2f° | %.3f | %.1f" % (
                p["triangles"], p["similarity"], "".join(" (after %s)" % f for f in p["failed"]), p["nodes"],
                p["tets"], p["dmin_min"], p["dmin_mean"], p["rasp_mean"], p["seconds"])
        line = ("| %s | %d | %d, %.4f | %d | %d (1 : %.0f) | %.2f° / %.2f° | %.3f | %.3f | %.3f | "
                "%.1f / %.1f / %.1f | %.0f | %s |") % (
            name + ("" if r == args.r else " (r %g)" % r), vox, tri, sim, vm["nodes"], vm["tetrahedra"],
            vm["voxels_per_tetrahedron"], q["min_dihedral_degrees"]["min"], q["min_dihedral_degrees"]["mean"],
            q["gamma"]["mean"], q["radius_aspect"]["mean"], q["edge_aspect"]["mean"], rep["seconds"]["volume"],
            vm["tetgen_seconds"], wall, rss, peer_cols)
        print(line, flush=True)
        lines.append(line)
    name = "volume_mesh_%s.md" % args.tag if args.flags else "volume_mesh.md"
    with open(os.path.join(out_root, "..", name), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
