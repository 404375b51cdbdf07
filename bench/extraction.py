#!/usr/bin/python3
"""Feature extraction (issue 20): how much of each fracture the model keeps, whether every
true sheet is found in its plane, the similarity against the raw phase with and without
extraction, each step's time and the run's peak memory.

Usage: /usr/bin/python3 bench/extraction.py [BUILD_DIR] [--paper] [--FLAG=VALUE ...]
  Volumes: NETL and DPM (../shared/data, skipped when absent) and the phantom presets
  sample, thick_slab and rough_network (generated under bench/out/extraction); --paper
  adds the 1012 x 1024 x 931 preset (bench/data, generated if absent; minutes), read once
  with `cat` beside it to show the machine's state. Other --FLAG=VALUE arguments are passed
  to the extraction run (for example --separate_fit_rings=0 to compare with the paper's test).
Writes bench/out/extraction.md and prints it.
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("SHEETMESH_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))
COMMON = ["--r=7", "--output_formats=ply", "--similarity_hausdorff=false", "--similarity_grid_rates="]


def timed(cmd):
    """Runs cmd; returns (wall seconds, the child's peak RSS in MiB)."""
    start = time.monotonic()
    with tempfile.TemporaryFile() as err:
        child = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.monotonic() - start
        if os.waitstatus_to_exitcode(status) != 0:
            err.seek(0)
            raise RuntimeError("%s failed: %s" % (" ".join(cmd), err.read().decode()))
    return wall, usage.ru_maxrss / 1024.0


def report(cli, command, vol, out, extra=()):
    wall, rss = timed([cli, command, vol, "-o", out] + COMMON + list(extra))
    return json.load(open(os.path.join(out, "report.json"))), wall, rss


def angle(a, b):
    c = abs(sum(x * y for x, y in zip(a, b))) / math.sqrt(sum(x * x for x in a) * sum(y * y for y in b))
    return math.degrees(math.acos(min(1.0, c)))


def matched(rep, truth):
    """Per true sheet: the smallest normal error among the pieces holding at least a tenth
    of its voxels' worth and lying in its band."""
    errors = []
    for s in truth["sheets"]:
        band = s["aperture"]["max"] / 2 + s["undulation"] + 2
        best = None
        for p in rep.get("pieces", []):
            d = abs(sum((c - o) * n for c, o, n in zip(p["centroid"], s["center"], s["normal"])))
            if d <= band and p["voxels"] >= s["voxels"] / 10:
                a = angle(p["normal"], s["normal"])
                best = a if best is None else min(best, a)
        errors.append(best)
    return errors


def volumes(cli, out_root):
    vols = []
    for name, f in [("NETL fracture", "netl_binary_fracture_small.tif"),
                    ("DPM junction", "dpm_3fractures_100x100x100_u8.raw")]:
        path = os.path.join(SHARED, f)
        if os.path.exists(path):
            vols.append((name, path, [], None))
        else:
            print("skipping %s: %s is absent" % (name, path))
    for preset, dims in [("sample", "128,112,96"), ("thick_slab", "100,100,111"),
                         ("rough_network", "160,160,160")]:
        raw = os.path.join(out_root, preset + ".raw")
        if not os.path.exists(raw):
            subprocess.run([cli, "phantom", "--preset=" + preset, "-o", raw], check=True,
                           capture_output=True)
        vols.append(("preset " + preset, raw, ["--dims=" + dims], json.load(open(raw + ".truth.json"))))
    if "--paper" in sys.argv:
        raw = os.path.join(ROOT, "bench", "data", "paper_1012x1024x931_u8.raw")
        if not os.path.exists(raw):
            os.makedirs(os.path.dirname(raw), exist_ok=True)
            subprocess.run([cli, "phantom", "--preset=paper", "-o", raw], check=True, capture_output=True)
        vols.append(("preset paper", raw, [], json.load(open(raw + ".truth.json"))))
    return vols


SEEDS = [1, 2, 3]


def spread(values):
    """The mean of values, with their range when there are several."""
    mean = sum(values) / len(values)
    if len(values) == 1:
        return "%.3f" % mean
    return "%.3f (%.3f–%.3f)" % (mean, min(values), max(values))


RUN_FLAGS = [a for a in sys.argv[1:] if a.startswith("--") and a != "--paper"]


def main():
    build = next((a for a in sys.argv[1:] if not a.startswith("--")), os.path.join(ROOT, "build"))
    cli = os.path.join(build, "worker", "pipeline", "sheetmesh-pipeline")
    out_root = os.path.join(ROOT, "bench", "out", "extraction")
    os.makedirs(out_root, exist_ok=True)
    lines = ["| volume | kept of the phase (specks / crossings / minor pieces dropped) | pieces, sheets | "
             "true sheets within 10° (errors) | similarity vs raw: without / with extraction (mean of "
             "surface seeds 1-3, range) | "
             "refine / detect / separate / remove / recover s | run wall s, peak MiB | separate.r, M used |",
             "|---|---|---|---|---|---|---|---|"]
    for name, vol, extra, truth in volumes(cli, out_root):
        d = os.path.join(out_root, name.replace(" ", "_"))
        if name == "preset paper":
            start = time.monotonic()
            subprocess.run("cat '%s' > /dev/null" % vol, shell=True, check=True)
            print("reading %s with cat: %.1f s" % (vol, time.monotonic() - start), flush=True)
        plain, _, _ = report(cli, "surface", vol, d + "_surface", extra)
        ext, wall, rss = report(cli, "run", vol, d + "_run", extra + ["--extract"] + RUN_FLAGS)
        # The surface's generators are drawn at random: the similarity moves by about 0.01
        # from seed to seed, so small volumes are measured over three seeds.
        sim_plain = [plain["similarity"]["similarity"]]
        sim_ext = [ext["similarity"]["raw"]["similarity"]]
        if name != "preset paper":
            for seed in SEEDS[1:]:
                sim_plain.append(report(cli, "surface", vol, d + "_surface", extra + [
                    "--surface_seed=%d" % seed])[0]["similarity"]["similarity"])
                sim_ext.append(report(cli, "run", vol, d + "_run", extra + [
                    "--extract", "--surface_seed=%d" % seed] + RUN_FLAGS)[0]["similarity"]["raw"]["similarity"])
        e = ext["extraction"]
        t = e["retention"]
        steps = {s["step"]: s["seconds"] for s in e["steps"]}
        match = "-"
        if truth:
            m = matched(ext, truth)
            match = "%d of %d (%s)" % (sum(x is not None and x <= 10 for x in m), len(m),
                                       ", ".join("%.1f°" % x if x is not None else "none" for x in m))
        line = "| %s | %.4f (%d / %d / %d of %d) | %d, %d | %s | %s / %s | %s | %.1f, %.0f | %.1f, %d |" % (
            name, t["fraction_kept"], t["dropped_specks"], t["dropped_at_crossings"],
            t["dropped_minor_pieces"], t["input_voxels"], e["pieces"], e["sheets"], match,
            spread(sim_plain), spread(sim_ext),
            " / ".join("%.2f" % steps[k] for k in ["refine", "detect", "separate", "remove_minor", "recover"]),
            wall, rss, e["scale"]["separate.r"]["value"], e["scale"]["M"]["value"])
        print(line, flush=True)
        lines.append(line)
    with open(os.path.join(out_root, "..", "extraction.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
