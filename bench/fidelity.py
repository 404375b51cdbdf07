#!/usr/bin/python3
"""Fidelity per element: sheetmesh's one-layer surface against a peer at equal triangle count.

The peer is marching cubes (scikit-image) on the binary sheet phase, decimated with VTK's
quadric decimation to the triangle count sheetmesh produced; it is a closed surface and is
scored by the volume it encloses. Both are scored by sheetmesh's own scorer (formula 5).

Usage: /usr/bin/python3 bench/fidelity.py [BUILD_DIR] [--radii 3,4,5,7,11,15]
Writes bench/out/fidelity.md and prints the table.
"""
import argparse
import json
import os
import subprocess
import sys

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
    for name, args, dims in [
        ("phantom sample", ["--preset=sample"], (128, 112, 96)),
        ("phantom 192^3", ["--phantom_dims=192x192x192", "--seed=3", "--sheets=4",
                           "--aperture=5", "--specks=0"], (192, 192, 192)),
    ]:
        raw = os.path.join(out_dir, "%s_%dx%dx%d_u8.raw" % (name.replace(" ", "_").replace("^", ""), *dims))
        if not os.path.exists(raw):
            run([cli, "phantom", "-o", raw] + args)
        vols.append((name, raw, dims, 255))
    return vols


def ours(cli, raw, value, r, out_dir):
    d = os.path.join(out_dir, "ours_r%g" % r)
    run([cli, "surface", raw, "--labels=%g" % value, "--r=%g" % r, "-o", d, "--output_formats=ply",
         "--similarity_hausdorff=false", "--similarity_grid_rates="])
    rep = json.load(open(os.path.join(d, "report.json")))
    return rep["surface"]["triangles"], rep["similarity"]["similarity"], rep["similarity"]["shell_similarity"]


def peer(cli, raw, dims, value, triangles, out_dir):
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
    path = os.path.join(out_dir, "peer_%d.ply" % triangles)
    w = vtk.vtkPLYWriter()
    w.SetFileName(path)
    w.SetInputData(dec.GetOutput())
    w.Write()
    s = json.loads(run([cli, "score", raw, path, "--labels=%g" % value, "--closed", "--json",
                        "--similarity_hausdorff=false"]))
    return dec.GetOutput().GetNumberOfCells(), s["similarity"], len(faces)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=os.path.join(ROOT, "build"))
    ap.add_argument("--radii", default="3,4,5,7,11,15")
    args = ap.parse_args()
    cli = os.path.join(args.build, "worker", "pipeline", "sheetmesh-pipeline")
    out_root = os.path.join(ROOT, "bench", "out", "fidelity")
    os.makedirs(out_root, exist_ok=True)
    radii = [float(r) for r in args.radii.split(",")]
    lines = ["| volume | r | triangles | sheetmesh (face) | sheetmesh (shell) | peer triangles | peer | ahead |",
             "|---|---|---|---|---|---|---|---|"]
    for name, raw, dims, value in volumes(cli, out_root):
        vdir = os.path.join(out_root, name.replace(" ", "_").replace("^", ""))
        os.makedirs(vdir, exist_ok=True)
        for r in radii:
            tri, sim, shell = ours(cli, raw, value, r, vdir)
            ptri, psim, full = peer(cli, raw, dims, value, tri, vdir)
            best = max(sim, shell)
            line = "| %s | %g | %d | %.4f | %.4f | %d (of %d) | %.4f | %s |" % (
                name, r, tri, sim, shell, ptri, full, psim, "yes" if best >= psim else "no")
            print(line, flush=True)
            lines.append(line)
    with open(os.path.join(out_root, "..", "fidelity.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
