#!/usr/bin/python3
"""Fidelity per element: sheetmesh's surface against a peer at equal triangle count.

The peer is marching cubes (scikit-image) on the binary sheet phase, decimated with VTK's
quadric decimation to the triangle count sheetmesh produced; it is a closed surface and is
scored by the volume it encloses. Both are scored by sheetmesh's own scorer (formula 5).

For each volume and triangle budget, sheetmesh's `surface --triangles N` picks r; the mesh
at that r, each piece a sheet or a body (surface.representation auto), is timed and scored
(formula 5, Dice, Hausdorff), and so is the same run with every piece a sheet
(surface.representation sheet, the one-layer surface alone); the peer is decimated to the
same count, timed (marching cubes plus decimation) and scored the same way. Volumes: NETL
and DPM (../shared/data, skipped when absent), the phantom sample, the presets thick_slab,
rough_slab (walls rough and not parallel), rough_network and vuggy_network (thin sheets
opening into vugs), a 192³ phantom, and a planar constant-aperture junction built here.

Usage: /usr/bin/python3 bench/fidelity.py [BUILD_DIR] [--budgets 100,200,...]
           [--volumes NAME,...] [--sheets_only] [--FLAG=VALUE]
--volumes keeps the volumes whose name holds one of the words; --sheets_only skips the
automatic choice (the sheets-only run gives the row). Other --FLAG=VALUE arguments go to
sheetmesh's surface runs (e.g. --surface_fit_walls=false, --surface_mesher=midsurface).
Writes bench/out/fidelity.md and prints the table.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
from skimage import measure
import vtk
from vtk.util import numpy_support

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("SHEETMESH_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))


def run(cmd):
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return out.stdout


def volumes(cli, out_dir):
    """(name, raw path, dims (x, y, z), sheet value) of the benchmark volumes."""
    vols = []
    netl = os.path.join(SHARED, "netl_binary_fracture_small.tif")
    if os.path.exists(netl):
        raw = os.path.join(out_dir, "netl_200x42x100_u8.raw")
        if not os.path.exists(raw):
            run([cli, "convert", netl, "-o", raw, "--out_format=raw"])
        vols.append(("NETL fracture", raw, (200, 42, 100), 255))
    dpm = os.path.join(SHARED, "dpm_3fractures_100x100x100_u8.raw")
    if os.path.exists(dpm):
        vols.append(("DPM junction", dpm, (100, 100, 100), 255))
    else:
        print("shared data absent: benchmarking the phantoms only", file=sys.stderr)
    junction = os.path.join(out_dir, "planar_junction_120x120x120_u8.raw")
    if not os.path.exists(junction):
        planar_junction().tofile(junction)
    vols.append(("planar junction", junction, (120, 120, 120), 255))
    for name, args, dims in [
        ("phantom sample", ["--preset=sample"], (128, 112, 96)),
        ("phantom 192^3", ["--phantom_dims=192x192x192", "--seed=3", "--sheets=4",
                           "--aperture=5", "--specks=0"], (192, 192, 192)),
        ("preset thick_slab", ["--preset=thick_slab"], (100, 100, 111)),
        ("preset rough_slab", ["--preset=rough_slab"], (100, 100, 111)),
        ("preset rough_network", ["--preset=rough_network"], (160, 160, 160)),
        ("preset vuggy_network", ["--preset=vuggy_network"], (160, 160, 160)),
    ]:
        raw = os.path.join(out_dir, "%s_%dx%dx%d_u8.raw" % (name.replace(" ", "_").replace("^", ""), *dims))
        if not os.path.exists(raw):
            run([cli, "phantom", "-o", raw] + args)
        vols.append((name, raw, dims, 255))
    return vols


def planar_junction():
    """Three planar slabs of constant aperture 4 in a 120^3 box: two crossing at right angles
    and one ending against them (a T), the kind of sheet a closed surface encloses exactly."""
    v = np.zeros((120, 120, 120), dtype=np.uint8)  # (z, y, x)
    v[58:62, 10:110, 10:110] = 255   # z = 58..61
    v[10:110, 10:110, 58:62] = 255   # x = 58..61
    v[62:110, 28:32, 60:110] = 255   # y = 28..31, above the first, against the second
    return v


def dims_flag(raw, dims):
    return [] if "_%dx%dx%d_" % dims in os.path.basename(raw) else ["--dims=%d,%d,%d" % dims]


def ours(cli, raw, dims, value, budget, out_dir, extra, representation="auto"):
    """sheetmesh at `budget` triangles (`surface --triangles`, its search included in the
    time): (triangles, S, shell S, Dice, Hausdorff, seconds, r, decimated, representation:
    bodies and pieces)."""
    d = os.path.join(out_dir, "ours_%s_%d" % (representation, budget))
    start = time.monotonic()
    run([cli, "surface", raw, "--labels=%g" % value, "-o", d, "--output_formats=ply",
         "--similarity_grid_rates=", "--triangles=%d" % budget,
         "--surface_representation=" + representation] + dims_flag(raw, dims) + extra)
    seconds = time.monotonic() - start
    rep = json.load(open(os.path.join(d, "report.json")))
    sim = rep["similarity"]
    search = rep["radius_search"]
    pieces = rep.get("representation", {}).get("pieces", [])
    bodies = [p for p in pieces if p["representation"] == "body"]
    lenses = sum(1 for p in bodies if p.get("part_of", -1) >= 0)
    kinds = "%d of %d%s" % (len(bodies), len(pieces) - lenses,
                            " (%d lenses)" % lenses if lenses else "")
    return (rep["surface"]["triangles"], sim["similarity"], sim["shell_similarity"], sim["dice"],
            sim.get("hausdorff_voxels"), seconds, search["chosen_r"], "decimated_to" in search,
            kinds)


def peer(cli, raw, dims, value, triangles, out_dir):
    """Marching cubes decimated to `triangles`: (triangles, S, Dice, Hausdorff, full count,
    seconds of marching cubes and decimation)."""
    start = time.monotonic()
    nx, ny, nz = dims
    vol = np.fromfile(raw, dtype=np.uint8).reshape(nz, ny, nx)
    binary = np.pad((vol == value).astype(np.float32), 1)
    verts, faces, _, _ = measure.marching_cubes(binary, level=0.5)
    xyz = verts[:, ::-1] - 1.0  # (z, y, x) of the padded array -> voxel (x, y, z)
    points = vtk.vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(xyz), deep=True))
    cells = vtk.vtkCellArray()
    conn = np.hstack([np.full((len(faces), 1), 3), faces]).astype(np.int64).ravel()
    cells.SetCells(len(faces), numpy_support.numpy_to_vtkIdTypeArray(conn, deep=True))
    poly = vtk.vtkPolyData()
    poly.SetPoints(points)
    poly.SetPolys(cells)
    dec = vtk.vtkQuadricDecimation()
    dec.SetInputData(poly)
    dec.SetTargetReduction(max(0.0, 1.0 - triangles / float(len(faces))))
    dec.Update()
    seconds = time.monotonic() - start
    path = os.path.join(out_dir, "peer_%d.ply" % triangles)
    w = vtk.vtkPLYWriter()
    w.SetFileName(path)
    w.SetInputData(dec.GetOutput())
    w.Write()
    s = json.loads(run([cli, "score", raw, path, "--labels=%g" % value, "--closed", "--json"] +
                       dims_flag(raw, dims)))
    return (dec.GetOutput().GetNumberOfCells(), s["similarity"], s["dice"],
            s.get("hausdorff_voxels"), len(faces), seconds)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=os.path.join(ROOT, "build"))
    ap.add_argument("--budgets", default="100,200,500,1000,2000,5000,10000,20000")
    ap.add_argument("--volumes", default="", help="words of the volumes' names to keep")
    ap.add_argument("--sheets_only", action="store_true")
    args, extra = ap.parse_known_args()
    cli = os.path.join(args.build, "worker", "pipeline", "sheetmesh-pipeline")
    out_root = os.path.join(ROOT, "bench", "out", "fidelity")
    os.makedirs(out_root, exist_ok=True)
    budgets = [int(b) for b in args.budgets.split(",")]
    lines = ["| volume | budget | triangles (r; dec.: decimated) | bodies of pieces | S ours (shell) "
             "| S sheets only | S peer | Δ S | shortfall ratio "
             "| Dice ours / peer | Hausdorff ours / peer | s ours / peer |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    keep = [w for w in args.volumes.split(",") if w]
    for name, raw, dims, value in volumes(cli, out_root):
        if keep and not any(w in name for w in keep):
            continue
        vdir = os.path.join(out_root, name.replace(" ", "_").replace("^", ""))
        os.makedirs(vdir, exist_ok=True)
        last = None
        for budget in budgets:
            try:
                if args.sheets_only:
                    tri, sim, shell, dice, haus, secs, r, dec, kinds = ours(
                        cli, raw, dims, value, budget, vdir, extra, "sheet")
                    sheet_only = sim
                else:
                    tri, sim, shell, dice, haus, secs, r, dec, kinds = ours(
                        cli, raw, dims, value, budget, vdir, extra)
                    sheet_only = ours(cli, raw, dims, value, budget, vdir, extra, "sheet")[1]
            except subprocess.CalledProcessError as e:
                line = "| %s | %d | refused: %s |" % (name, budget, e.stderr.strip().splitlines()[-1])
                print(line, flush=True)
                lines.append(line)
                continue
            if tri == last:
                continue  # the finest mesh r_min allows, reached already
            last = tri
            ptri, psim, pdice, phaus, full, psecs = peer(cli, raw, dims, value, tri, vdir)
            ratio = (1 - sim) / (1 - psim) if psim < 1 else float("inf")
            line = ("| %s | %d | %d (%.2f%s) | %s | %.4f (%.4f) | %.4f | %.4f | %+.4f | %.2f | "
                    "%.3f / %.3f | %.1f / %.1f | %.2f / %.2f |") % (
                name, budget, tri, r, ", dec." if dec else "", kinds, sim, shell, sheet_only, psim,
                sim - psim, ratio, dice, pdice, haus or 0, phaus or 0, secs, psecs)
            print(line, flush=True)
            lines.append(line)
    with open(os.path.join(out_root, "..", "fidelity.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
