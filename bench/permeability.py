#!/usr/bin/python3
"""The permeability tensor through the whole workflow (issue 46), against known answers.

Volumes built here with numpy, voxels of 5 µm (`--unit=um --spacing=5,5,5`):
- `crossing slabs`: two slabs 4 voxels thick through a 96³ box, z = 46..49 and x = 46..49:
  K = k_m I + Σ a³/(12 L) (I − n nᵀ) with a = 20 µm, L = 480 µm;
- `tilted slab`: one slab 4 voxels thick (measured along its normal) through the box, tilted
  30° about y: in its plane k_m + a³/(12 L cos 30°), across it k_m, the least principal
  direction its normal;
and the real scans NETL and DPM (../shared/data; their voxel size taken as 5 µm).

Each is run as a user would, `sheetmesh-pipeline run VOLUME --flow --r=R` (extraction on;
the surface's fitted apertures are what the flow sees), at r = 3, 5 and 7: the tensor's
diagonal against the answer, the principal direction's angle, the sheets' share of the flux,
the solver's iterations and time against the volume mesh's.

Usage: /usr/bin/python3 bench/permeability.py [BUILD_DIR]
Writes bench/out/permeability.md and prints it.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("SHEETMESH_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))
VOXEL_M = 5e-6
K_M = 1e-18


def slabs(path):
    v = np.zeros((96, 96, 96), dtype=np.uint8)  # (z, y, x)
    v[46:50, :, :] = 255
    v[:, :, 46:50] = 255
    v.tofile(path)
    a, l = 4 * VOXEL_M, 96 * VOXEL_M
    f = a ** 3 / (12 * l)
    return [K_M + f, K_M + 2 * f, K_M + f], None


def tilted(path):
    z, y, x = np.mgrid[0:96, 0:96, 0:96]
    t = math.radians(30)
    n = (math.sin(t), 0.0, math.cos(t))
    d = (x - 47.5) * n[0] + (z - 47.5) * n[2]
    ((np.abs(d) < 2) * 255).astype(np.uint8).tofile(path)
    a, l = 4 * VOXEL_M, 96 * VOXEL_M
    along = K_M + a ** 3 / (12 * l * math.cos(t))
    # In the frame of the fracture: along, along, k_m; the diagonal in x, y, z follows.
    nn = np.outer(n, n)
    k = K_M * np.eye(3) + (along - K_M) * (np.eye(3) - nn)
    return [k[0, 0], k[1, 1], k[2, 2]], n


def run(cli, vol, out, r, extra):
    p = subprocess.run([cli, "run", vol, "--flow", "--unit=um", "--spacing=5,5,5",
                        "--r=%g" % r, "-o", out, "--output_previews=false",
                        "--output_formats=ply", "--output_volume_formats=vtu",
                        "--similarity_hausdorff=false"] + extra,
                       capture_output=True, text=True)
    if p.returncode != 0:
        return None, p.stderr.strip().splitlines()[-1]
    return json.load(open(os.path.join(out, "report.json"))), None


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build-tests")
    cli = os.path.join(build, "worker", "pipeline", "sheetmesh-pipeline")
    tmp = tempfile.mkdtemp(prefix="sheetmesh_flow_")
    cases = []
    p = os.path.join(tmp, "slabs_96x96x96_u8.raw")
    cases.append(("crossing slabs", p, ["--labels=255"]) + slabs(p))
    p = os.path.join(tmp, "tilted_96x96x96_u8.raw")
    cases.append(("tilted slab", p, ["--labels=255"]) + tilted(p))
    for name, f in [("NETL", "netl_binary_fracture_small.tif"),
                    ("DPM", "dpm_3fractures_100x100x100_u8.raw")]:
        full = os.path.join(SHARED, f)
        if os.path.exists(full):
            cases.append((name, full, ["--labels=255"], None, None))
        else:
            print("%s: %s absent, skipped" % (name, full))
    lines = ["| volume | r | k_xx / k_yy / k_zz (darcy) | against the answer | least principal "
             "direction off the normal | permeameters: mesh / image per axis | sheets' share of "
             "the flux | tetrahedra | CG iterations | flow s (image s) / volume mesh s |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, vol, extra, answer, normal in cases:
        for r in (3, 5, 7):
            rep, err = run(cli, vol, os.path.join(tmp, "%s_%g" % (name.replace(" ", "_"), r)), r,
                           extra)
            if rep is None:
                lines.append("| %s | %g | fails: %s |" % (name, r, err))
                continue
            k = rep["flow"]["permeability_m2"]
            diag = [k[i][i] for i in range(3)]
            darcy = " / ".join("%.3g" % (d / 9.869233e-13) for d in diag)
            against = "—"
            if answer:
                against = " / ".join("%+.1f%%" % (100 * (d - a) / a) for d, a in zip(diag, answer))
            angle = "—"
            if normal is not None:
                least = rep["flow"]["principal_directions"][2]
                c = abs(sum(u * v for u, v in zip(least, normal)))
                angle = "%.2f°" % math.degrees(math.acos(min(1.0, c)))
            share = " / ".join("%.2f" % s for s in rep["flow"]["fracture_share_of_flux"])
            image = rep["flow"].get("image_reference", {})
            ratio = " / ".join("%.3f" % v for v in image.get("mesh_to_image_per_axis", [])) or \
                image.get("skipped", "—")
            secs = rep["seconds"]
            lines.append("| %s | %g | %s | %s | %s | %s | %s | %d | %s | %.2f (%.2f) / %.2f |" % (
                name, r, darcy, against, angle, ratio, share, rep["volume_mesh"]["tetrahedra"],
                "/".join(str(i) for i in rep["flow"]["iterations"]),
                secs.get("flow", 0), image.get("seconds", 0), secs.get("volume", 0)))
            print(lines[-1], flush=True)
    text = "\n".join(lines)
    os.makedirs(os.path.join(ROOT, "bench", "out"), exist_ok=True)
    open(os.path.join(ROOT, "bench", "out", "permeability.md"), "w").write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
