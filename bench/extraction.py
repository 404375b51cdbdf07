#!/usr/bin/python3
"""Feature extraction: similarity against the raw phase with and without extraction, piece
counts against the phantoms' ground truth, and each step's wall time.

Usage: /usr/bin/python3 bench/extraction.py [BUILD_DIR] [--paper]
  --paper also runs the 1012 x 1024 x 931 phantom (bench/data, generated if absent; minutes).
Writes bench/out/extraction.md and prints it.
"""
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("SHEETMESH_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def report(cli, command, vol, out, extra=()):
    run([cli, command, vol, "-o", out, "--r=7", "--output_formats=ply", "--similarity_hausdorff=false",
         "--similarity_grid_rates="] + list(extra))
    return json.load(open(os.path.join(out, "report.json")))


def angle(a, b):
    c = abs(sum(x * y for x, y in zip(a, b))) / math.sqrt(sum(x * x for x in a) * sum(y * y for y in b))
    return math.degrees(math.acos(min(1.0, c)))


def truth_match(rep, truth):
    """Per truth sheet: the smallest normal error among the planar pieces (planarity >= 0.9)
    whose centroid lies in its band; and the pieces that are not planar (mixes of sheets)."""
    out = []
    pieces = rep.get("pieces", [])
    for s in truth["sheets"]:
        band = s["aperture"]["max"] / 2 + s["undulation"] + 2
        best = None
        for p in pieces:
            d = abs(sum((c - o) * n for c, o, n in zip(p["centroid"], s["center"], s["normal"])))
            if d <= band and p["planarity"] >= 0.9:
                a = angle(p["normal"], s["normal"])
                best = a if best is None else min(best, a)
        out.append(best)
    mixed = [p for p in pieces if p["planarity"] < 0.9]
    return out, len(mixed), sum(p["voxels"] for p in mixed)


def main():
    build = next((a for a in sys.argv[1:] if not a.startswith("--")), os.path.join(ROOT, "build"))
    cli = os.path.join(build, "worker", "pipeline", "sheetmesh-pipeline")
    out_root = os.path.join(ROOT, "bench", "out", "extraction")
    os.makedirs(out_root, exist_ok=True)
    vols = []
    for name, f in [("NETL fracture", "netl_binary_fracture_small.tif"),
                    ("DPM junction", "dpm_3fractures_100x100x100_u8.raw")]:
        if os.path.exists(os.path.join(SHARED, f)):
            vols.append((name, os.path.join(SHARED, f), None))
    for name, dims, args in [("phantom 128^3 seed 4", "128x128x128", ["--seed=4", "--sheets=3", "--specks=30"]),
                             ("phantom 192^3 seed 3", "192x192x192", ["--seed=3", "--sheets=4", "--specks=-1"])]:
        raw = os.path.join(out_root, "phantom_%s_%s_u8.raw" % (args[0].split("=")[1], dims))
        if not os.path.exists(raw):
            run([cli, "phantom", "-o", raw, "--phantom_dims=" + dims] + args)
        vols.append((name, raw, json.load(open(raw + ".truth.json"))))
    if "--paper" in sys.argv:
        raw = os.path.join(ROOT, "bench", "data", "paper_1012x1024x931_u8.raw")
        if not os.path.exists(raw):
            run([cli, "phantom", "--preset=paper", "-o", raw])
        vols.append(("paper phantom 1012x1024x931", raw, json.load(open(raw + ".truth.json"))))
    lines = ["| volume | similarity vs raw, no extraction | with extraction: vs raw | vs model | "
             "pieces | truth sheets matched by a planar piece (normal error) | refine / detect / separate / remove / recover / surface, s |",
             "|---|---|---|---|---|---|---|"]
    for name, vol, truth in vols:
        d = os.path.join(out_root, name.replace(" ", "_").replace("^", ""))
        plain = report(cli, "surface", vol, d + "_surface")
        ext = report(cli, "run", vol, d + "_run")
        steps = {s["step"]: s["seconds"] for s in ext["extraction"]["steps"]}
        match = "-"
        if truth:
            m, mixed, mixed_voxels = truth_match(ext, truth)
            match = "%d of %d within 10° (%s); %d mixed pieces (%d voxels)" % (
                sum(x is not None and x <= 10 for x in m), len(m),
                ", ".join("%.1f°" % x if x is not None else "none" for x in m), mixed, mixed_voxels)
        line = "| %s | %.4f | %.4f | %.4f | %d | %s | %s / %.1f |" % (
            name, plain["similarity"]["similarity"], ext["similarity"]["raw"]["similarity"],
            ext["similarity"]["similarity"], ext["extraction"]["pieces"], match,
            " / ".join("%.1f" % steps[k] for k in ["refine", "detect", "separate", "remove_minor", "recover"]),
            ext["seconds"]["surface"])
        print(line, flush=True)
        lines.append(line)
    with open(os.path.join(out_root, "..", "extraction.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
