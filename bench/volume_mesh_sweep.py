#!/usr/bin/python3
"""The volume mesh swept as a user would run it: every benchmark volume and phantom preset
x r in {2, 3, 4, 5, 7, 11, 15} x {surface, run} (run extracts first), each with
`--volume_mesh`. Per run: success or the error's first words, the minimum and mean
dihedral angle, tetrahedra, sheet triangles, tetrahedra per sheet triangle, the similarity
S, the volume stage's seconds and TetGen's own.

Usage: /usr/bin/python3 bench/volume_mesh_sweep.py [BUILD_DIR] [--r 2,3,4,5,7,11,15]
    [--modes surface,run] [--only NAME,...] [--flags "..."] [--tag NAME] [--jobs 1]
Writes bench/out/volume_mesh_sweep[_TAG].md (a table and a summary) and prints it. The
volumes are bench/fidelity.py's (NETL and DPM from ../shared/data when present, the planar
junction, the phantoms) and every preset of `sheetmesh-pipeline phantom`.
"""
import argparse
import concurrent.futures
import json
import os
import shlex
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fidelity  # noqa: E402

ROOT = fidelity.ROOT
PRESETS = ["shallow_network", "grazing_sheet"]  # besides fidelity.py's volumes


def preset_volumes(cli, out_dir):
    vols = []
    for preset in PRESETS:
        raw = os.path.join(out_dir, "preset_%s.raw" % preset)
        if not os.path.exists(raw):
            r = subprocess.run([cli, "phantom", "--preset=" + preset, "-o", raw], capture_output=True, text=True)
            if r.returncode != 0:
                print("preset %s: %s" % (preset, r.stderr.strip()), file=sys.stderr)
                continue
        truth = json.load(open(raw + ".truth.json"))
        dims = tuple(truth["dims"]) if "dims" in truth else None
        vols.append(("preset " + preset, raw, dims, 255))
    return vols


def one(cli, name, raw, dims, value, mode, r, out_dir, flags):
    d = os.path.join(out_dir, "%s_%s_r%g" % (name.replace(" ", "_"), mode, r))
    cmd = [cli, mode, raw, "--labels=%g" % value, "--r=%g" % r, "-o", d, "--volume_mesh",
           "--output_formats=ply", "--output_volume_formats=vtu", "--similarity_hausdorff=false",
           "--similarity_grid_rates="] + (fidelity.dims_flag(raw, dims) if dims else []) + flags
    t = time.perf_counter()
    try:
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    except subprocess.TimeoutExpired:
        return {"volume": name, "mode": mode, "r": r, "wall": 900, "exit": -1, "error": "over 900 s"}
    wall = time.perf_counter() - t
    row = {"volume": name, "mode": mode, "r": r, "wall": wall, "exit": res.returncode}
    if res.returncode != 0:
        err = (res.stderr.strip().splitlines() or ["?"])[-1]
        row["error"] = err.split(": ", 1)[-1][:90]
        return row
    rep = json.load(open(os.path.join(d, "report.json")))
    vm = rep["volume_mesh"]
    q = vm["quality"]["min_dihedral_degrees"]
    row.update(min=q["min"], mean=q["mean"], tets=vm["tetrahedra"], tris=rep["surface"]["triangles"],
               S=rep["similarity"]["similarity"], vol_s=rep["seconds"].get("volume", 0),
               tetgen_s=vm.get("tetgen_seconds", 0))
    row["per_tri"] = row["tets"] / max(1, row["tris"])
    row["wedge"] = vm.get("input_wedges", {}).get("narrowest_degrees", 360)
    row["repaired"] = vm.get("repaired_triangles", 0)
    row["thin_splits"] = vm.get("untangled", {}).get("thin_splits", 0)
    row["bodies"] = len(vm.get("bodies", []))
    row["body_tets"] = sum(b["tetrahedra"] for b in vm.get("bodies", []))
    return row


def table(rows):
    out = ["| volume | mode | r | result | min° | mean° | tets | sheet tris | tets/tri | S | volume s | TetGen s "
           "| input wedge° | removed tris | bodies (their tets) |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for x in rows:
        if "error" in x:
            out.append("| %s | %s | %g | **failed**: %s | | | | | | | | | | | |" % (
                x["volume"], x["mode"], x["r"], x["error"]))
        else:
            out.append("| %s | %s | %g | %s | %.2f | %.2f | %d | %d | %.1f | %.3f | %.2f | %.2f | %.2f | %d | %s |" % (
                x["volume"], x["mode"], x["r"], "ok" if x["min"] >= 10 else "min < 10°", x["min"], x["mean"],
                x["tets"], x["tris"], x["per_tri"], x["S"], x["vol_s"], x["tetgen_s"], x.get("wedge", 360),
                x.get("repaired", 0), "%d (%d)" % (x["bodies"], x["body_tets"]) if x.get("bodies") else ""))
    return out


def summary(rows):
    ok = [x for x in rows if "error" not in x]
    failed = [x for x in rows if "error" in x]
    slivers = [x for x in ok if x["min"] < 10]
    lines = ["", "%d runs: %d meshes with min dihedral >= 10°, %d with slivers, %d failed" % (
        len(rows), len(ok) - len(slivers), len(slivers), len(failed))]
    forced = [x for x in slivers if x.get("wedge", 360) < 10]
    lines.append("of the meshes with slivers, %d have an input wedge under 10° (sheets or a sheet and the box "
                 "meeting in an edge at that angle: no conforming mesh does better there)" % len(forced))
    repaired = [x for x in ok if x.get("repaired", 0) > 0]
    lines.append("runs with sheet triangles removed as a last resort: %d (%d triangles in all); with thin "
                 "crossing splits: %d" % (len(repaired), sum(x["repaired"] for x in repaired),
                                          sum(1 for x in ok if x.get("thin_splits", 0) > 0)))
    if ok:
        lines.append("min dihedral: lowest %.2f°, median %.2f°; mean dihedral lowest %.2f°" % (
            min(x["min"] for x in ok), statistics.median(x["min"] for x in ok), min(x["mean"] for x in ok)))
        mid = [x["per_tri"] for x in ok if 4 <= x["r"] <= 11]
        if mid:
            lines.append("tetrahedra per sheet triangle at r 4-11: median %.1f (range %.1f-%.1f)" % (
                statistics.median(mid), min(mid), max(mid)))
        ratio = [x["vol_s"] / x["tetgen_s"] for x in ok if x["tetgen_s"] > 0]
        if ratio:
            lines.append("volume stage / TetGen: median %.1fx, worst %.1fx" % (statistics.median(ratio), max(ratio)))
    with_bodies = [x for x in ok if x.get("bodies", 0) > 0]
    if with_bodies:
        lines.append("runs with bodies: %d, of them min >= 10°: %d; body regions with no tetrahedra: %d" % (
            len(with_bodies), sum(1 for x in with_bodies if x["min"] >= 10),
            sum(1 for x in with_bodies if x["body_tets"] == 0)))
    for x in failed:
        lines.append("failed: %s %s r=%g: %s" % (x["volume"], x["mode"], x["r"], x["error"]))
    return lines


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=os.path.join(ROOT, "build"))
    ap.add_argument("--r", default="2,3,4,5,7,11,15")
    ap.add_argument("--modes", default="surface,run")
    ap.add_argument("--only", default="")
    ap.add_argument("--flags", default="")
    ap.add_argument("--tag", default="")
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args()
    cli = os.path.join(a.build, "worker", "pipeline", "sheetmesh-pipeline")
    out_dir = os.path.join(ROOT, "bench", "out", "sweep" + ("_" + a.tag if a.tag else ""))
    os.makedirs(out_dir, exist_ok=True)
    vols = fidelity.volumes(cli, os.path.join(ROOT, "bench", "out")) + preset_volumes(cli, out_dir)
    if a.only:
        keep = a.only.split(",")
        vols = [v for v in vols if any(k in v[0] for k in keep)]
    radii = [float(x) for x in a.r.split(",")]
    modes = a.modes.split(",")
    flags = shlex.split(a.flags)
    work = [(name, raw, dims, value, mode, r) for name, raw, dims, value in vols for mode in modes for r in radii]
    t0 = time.time()
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        rows = list(pool.map(lambda w: one(cli, *w, out_dir, flags), work))
    lines = table(rows) + summary(rows)
    lines.append("(%d runs in %.0f s, %d at a time; flags: %s)" % (len(rows), time.time() - t0, a.jobs, a.flags or "none"))
    text = "\n".join(lines) + "\n"
    open(os.path.join(ROOT, "bench", "out", "volume_mesh_sweep%s.md" % ("_" + a.tag if a.tag else "")), "w").write(text)
    print(text)


if __name__ == "__main__":
    main()
