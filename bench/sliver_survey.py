#!/usr/bin/python3
"""What holds the slivers of a volume mesh sweep: for every run of a
`bench/volume_mesh_sweep.py` output folder whose mesh has a tetrahedron under 10° although
no two facets meet at under 10° (the report's `input_wedges`), the worst tetrahedron's
corners on the sheets and on the box, whether one of its faces is a sheet face, and how
many tetrahedra under 10° there are by their number of corners on the sheets (0-4).

    /usr/bin/python3 bench/sliver_survey.py bench/out/sweep_TAG [--below 10]

A tetrahedron with three or four corners on the sheets spans a near contact between two
parts of the sheets (or rests on a sheet face with its fourth corner just off it): what
the improvement, which moves no sheet vertex, cannot open.
"""
import argparse
import glob
import json
import os
import sys

import meshio
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from volume_mesh import quality  # noqa: E402  (the per-tetrahedron dihedral angle)


def survey(run_dir, below):
    mesh = meshio.read(os.path.join(run_dir, "volume.vtu"))
    nodes, tets = mesh.points, mesh.cells_dict["tetra"]
    faces = kind = None
    for block, k in zip(mesh.cells, mesh.cell_data["kind"]):
        if block.type == "triangle":
            faces, kind = block.data, k
    sheet, box = faces[kind == 1], faces[kind != 1]
    on_sheet = np.zeros(len(nodes), bool)
    on_sheet[np.unique(sheet)] = True
    on_box = np.zeros(len(nodes), bool)
    on_box[np.unique(box)] = True
    dmin = quality(nodes, tets)[0]
    worst = tets[np.argmin(dmin)]
    sheet_faces = set(tuple(sorted(f)) for f in sheet)
    rests = any(tuple(sorted(np.delete(worst, i))) in sheet_faces for i in range(4))
    bad = tets[dmin < below]
    return {"slivers": len(bad), "sheet_corners": int(on_sheet[worst].sum()),
            "box_corners": int(on_box[worst].sum()), "on_sheet_face": rests,
            "by_sheet_corners": np.bincount(on_sheet[bad].sum(1), minlength=5).tolist()}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sweep_dir")
    ap.add_argument("--below", type=float, default=10.0)
    a = ap.parse_args()
    rows = []
    for report in sorted(glob.glob(os.path.join(a.sweep_dir, "*", "report.json"))):
        vm = json.load(open(report))["volume_mesh"]
        low = vm["quality"]["min_dihedral_degrees"]["min"]
        wedge = vm.get("input_wedges", {}).get("narrowest_degrees", 360)
        if low >= a.below or wedge < a.below:
            continue
        run = os.path.dirname(report)
        rows.append((os.path.basename(run), low, wedge, survey(run, a.below)))
    print("| run | min° | input wedge° | under %g° | worst: sheet corners | box corners | on a sheet face "
          "| under %g° by sheet corners 0-4 |" % (a.below, a.below))
    print("|---|---|---|---|---|---|---|---|")
    for name, low, wedge, s in rows:
        print("| %s | %.2f | %.1f | %d | %d | %d | %s | %s |" % (
            name, low, wedge, s["slivers"], s["sheet_corners"], s["box_corners"],
            "yes" if s["on_sheet_face"] else "no", " / ".join(map(str, s["by_sheet_corners"]))))
    held = sum(1 for r in rows if r[3]["sheet_corners"] >= 3)
    print("\n%d runs under %g° not forced by an input wedge; in %d the worst tetrahedron has three or "
          "four corners on the sheets (%d of them resting on a sheet face); median %d tetrahedra under "
          "%g° per run" % (len(rows), a.below, held,
                           sum(1 for r in rows if r[3]["sheet_corners"] >= 3 and r[3]["on_sheet_face"]),
                           int(np.median([r[3]["slivers"] for r in rows])) if rows else 0, a.below))


if __name__ == "__main__":
    main()
