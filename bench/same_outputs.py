#!/usr/bin/python3
"""Same outputs: runs a fixed set of offline commands on the benchmark volumes and keeps
every file they write, so that a change meant to keep behaviour can be checked against
the build before it.

  /usr/bin/python3 bench/same_outputs.py run BUILD_DIR OUT_DIR [--flags-of VERSION]
  /usr/bin/python3 bench/same_outputs.py compare OLD_OUT NEW_OUT

`run` writes OUT_DIR/<case>/... for every case; `compare` says, per case, which mesh files
differ in bytes and which report values differ (the version string and timings aside;
report values are matched by their key path, and paths only one side has are listed).
`--flags-of 0.8` spells the flags as 0.8.x did (before the one parameter schema).
"""
import json
import re
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("SHEETMESH_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))

# Flags whose spelling changed with the parameter schema (0.9.0): new -> 0.8.x.
OLD_SPELLING = {"--surface_method": "--method"}


def run(cmd, keep=None):
    """Runs `cmd`; with `keep` (a folder), a failure is kept as keep/status.txt (exit code
    and the error's last line) instead of raised, so that failures are compared too."""
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode == 0:
        return
    if keep is None:
        raise RuntimeError("%s failed: %s" % (" ".join(cmd), p.stderr))
    os.makedirs(keep, exist_ok=True)
    last = (p.stderr.strip().splitlines() or [""])[-1]
    with open(os.path.join(keep, "status.txt"), "w") as f:
        f.write("exit %d: %s\n" % (p.returncode, last))


def volumes(cli, data):
    vols = []
    netl = os.path.join(SHARED, "netl_binary_fracture_small.tif")
    if os.path.exists(netl):
        vols.append(("netl", netl))
    dpm = os.path.join(SHARED, "dpm_3fractures_100x100x100_u8.raw")
    if os.path.exists(dpm):
        vols.append(("dpm", dpm))
    for name, args, dims in [("sample", ["--preset=sample"], "128x112x96"),
                             ("p192", ["--dims=192x192x192", "--seed=3", "--sheets=4",
                                       "--aperture=5", "--specks=0"], "192x192x192"),
                             ("p128", ["--dims=128x128x128", "--seed=4", "--sheets=3",
                                       "--specks=30"], "128x128x128")]:
        raw = os.path.join(data, "%s_%s_u8.raw" % (name, dims))
        if not os.path.exists(raw):
            run([cli, "phantom", "-o", raw] + args)
        vols.append((name, raw))
    return vols


def cases(vol):
    return [("surface_r7", ["surface", vol, "--labels=255", "--r=7"]),
            ("surface_r4_paper", ["surface", vol, "--labels=255", "--r=4", "--surface_method=paper"]),
            ("run_r7_volume", ["run", vol, "--labels=255", "--r=7", "--volume_mesh"]),
            # The budget: r searched, the mesh decimated to it (with extraction's pieces).
            ("surface_t600", ["surface", vol, "--labels=255", "--triangles=600"]),
            ("run_t600", ["run", vol, "--labels=255", "--triangles=600"])]


def do_run(build, out, old):
    cli = os.path.join(build, "worker", "pipeline", "sheetmesh-pipeline")
    data = os.path.join(out, "_volumes")
    os.makedirs(data, exist_ok=True)
    for name, vol in volumes(cli, data):
        for case, cmd in cases(vol):
            d = os.path.join(out, name + "_" + case)
            if old:
                cmd = [OLD_SPELLING.get(a.split("=")[0], a.split("=")[0]) + a[len(a.split("=")[0]):]
                       for a in cmd]
            run([cli] + cmd + ["-o", d], keep=d)
            print("ran", name, case, flush=True)
            if case == "run_r7_volume":
                run([cli, "volume", os.path.join(d, "surface.ply"), "--volume", vol, "--labels=255",
                     "-o", d + "_volume_command"], keep=d + "_volume_command")


def leaves(j, path=""):
    if isinstance(j, dict):
        for k, v in j.items():
            yield from leaves(v, path + "." + k if path else k)
    elif isinstance(j, list) and j and all(isinstance(x, dict) for x in j):
        for i, v in enumerate(j):
            yield from leaves(v, "%s[%d]" % (path, i))
    else:
        yield path, j


IGNORED = ("sheetmesh_version", "seconds", "tetgen_seconds", "improvement.seconds")


# Report paths that 0.9.0 moved (the one parameter schema, results that list their own
# fields): old path -> new path.
MOVED = {
    "parameters.fold_angle_degrees": "parameters.surface.fold_angle",
    "parameters.generator_count": "parameters.surface.generators",
    "parameters.lloyd_max_iter": "parameters.surface.lloyd_max_iter",
    "parameters.lloyd_tol": "parameters.surface.lloyd_tol",
    "parameters.mean_thickness": "parameters.surface.thickness",
    "parameters.rim": "parameters.surface.rim",
    "parameters.seed": "parameters.surface.seed",
    "parameters.similarity_model": "parameters.similarity.model",
    "parameters.thickness_measure": "parameters.surface.thickness_measure",
    "parameters.vertex_placement": "parameters.surface.placement",
    "extraction.parameters.M": "extraction.min_object_voxels",
    "extraction.parameters.D_ang": "parameters.separate.D_ang",
    "extraction.parameters.separate_r": "parameters.separate.r",
    "extraction.parameters.separate": "parameters.separate.enabled",
    "extraction.parameters.remove_minor": "parameters.remove_minor.enabled",
    "extraction.parameters.refine": "parameters.refine.enabled",
    "extraction.parameters.refine_close_radius": "parameters.refine.close_radius",
    "extraction.parameters.refine_open_radius": "parameters.refine.open_radius",
    "volume_mesh.parameters.max_radius_edge_ratio": "parameters.tet.radius_edge_ratio",
    "volume_mesh.parameters.max_volume": "parameters.tet.max_volume",
    "volume_mesh.parameters.min_dihedral_degrees": "parameters.tet.min_dihedral",
    "volume_mesh.parameters.repair": "parameters.plc.repair",
    "volume_mesh.parameters.steiner_on_sheets": "parameters.tet.steiner_on_sheets",
    "volume_mesh.parameters.tetgen_switches": "volume_mesh.tetgen_switches",
}
for step in ("detect", "recover"):
    MOVED["extraction.parameters." + step] = "parameters.%s.enabled" % step
    for k in ("t", "R", "rounds"):
        MOVED["extraction.parameters.%s_%s" % (step, k)] = "parameters.%s.%s" % (step, k)


def moved(path, name):
    if path.startswith("scvd."):
        return "surface." + path
    if name == "volume_report.json" and path in ("surface", "box"):
        return {"surface": "input.path", "box": "input.dims"}[path]
    if name == "volume_report.json" and path != "files":
        return "volume_mesh." + path
    return MOVED.get(path, path)


def same_bytes(fa, fb):
    a, b = open(fa, "rb").read(), open(fb, "rb").read()
    # The version string aside.
    a = re.sub(rb"sheetmesh \d+\.\d+\.\d+", b"sheetmesh VERSION", a)
    b = re.sub(rb"sheetmesh \d+\.\d+\.\d+", b"sheetmesh VERSION", b)
    if fa.endswith(".vdb"):
        # OpenVDB writes a fresh UUID (36 characters from byte 21) into every file.
        a, b = a[:21] + a[57:], b[:21] + b[57:]
    return a == b


def compare(a, b):
    bad = 0
    for case in sorted(os.listdir(a)):
        if case.startswith("_") or not os.path.isdir(os.path.join(a, case)):
            continue
        da, db = os.path.join(a, case), os.path.join(b, case)
        for f in sorted(os.listdir(da)):
            fa, fb = os.path.join(da, f), os.path.join(db, f)
            if not os.path.exists(fb):
                print("%s: %s missing in the new outputs" % (case, f))
                bad += 1
            elif f.endswith(".json"):
                # Paths name the output folders, which differ.
                lb = dict(leaves(json.loads(open(fb).read().replace(b.rstrip("/"), "OUT"))))
                # Old paths are mapped only where the new report has no such path.
                la = {(k if k in lb else moved(k, f)): v for k, v in
                      leaves(json.loads(open(fa).read().replace(a.rstrip("/"), "OUT")))}
                for k in sorted(set(la) & set(lb)):
                    if any(k == i or k.endswith("." + i) or k.startswith(i + ".") for i in IGNORED):
                        continue
                    if la[k] != lb[k]:
                        print("%s: %s: %s = %r -> %r" % (case, f, k, la[k], lb[k]))
                        bad += 1
                only_a = sorted(set(la) - set(lb))
                only_b = sorted(set(lb) - set(la))
                if only_a:
                    print("%s: %s: only before: %s" % (case, f, ", ".join(only_a)))
                if only_b:
                    print("%s: %s: %d values only after (new fields)" % (case, f, len(only_b)))
            elif not same_bytes(fa, fb):
                print("%s: %s differs" % (case, f))
                bad += 1
        print("%s: compared %d files" % (case, len(os.listdir(da))), flush=True)
    print("differences: %d" % bad)
    return bad


def main():
    if len(sys.argv) >= 4 and sys.argv[1] == "run":
        do_run(sys.argv[2], sys.argv[3], "--flags-of" in sys.argv)
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(1 if compare(sys.argv[2], sys.argv[3]) else 0)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
