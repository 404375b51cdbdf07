#!/usr/bin/python3
"""Lists the tetrahedra of a volume mesh below a dihedral angle and what holds them there.

    /usr/bin/python3 bench/tet_slivers.py OUT/volume.vtu [--below 10]

For each tetrahedron below the angle: its smallest dihedral angle, its shortest and longest
edge, how many of its corners lie on sheet faces (the mesh's triangles), and for each of
its four faces whether it is a sheet face (S) and its widest corner angle in degrees.
Coordinates are the mesh's (physical units; voxels when the placement is the default).
"""
import argparse
import os
import sys

import meshio
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from volume_mesh import quality  # noqa: E402  (the per-tetrahedron dihedral angle)


def widest_corner(p):
    def corner(a, b, c):
        u, w = b - a, c - a
        return np.degrees(np.arccos(np.dot(u, w) / np.linalg.norm(u) / np.linalg.norm(w)))
    return max(corner(p[0], p[1], p[2]), corner(p[1], p[2], p[0]), corner(p[2], p[0], p[1]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh")
    parser.add_argument("--below", type=float, default=10.0, help="degrees")
    args = parser.parse_args()
    mesh = meshio.read(args.mesh)
    points, tets = mesh.points, mesh.cells_dict["tetra"]
    sheet = mesh.cells_dict.get("triangle", np.zeros((0, 3), int))
    sheet_faces = {tuple(sorted(f)) for f in sheet.tolist()}
    on_sheet = np.zeros(len(points), bool)
    on_sheet[sheet.ravel()] = True
    angle = quality(points, tets)[0]
    print(f"{args.mesh}: {len(tets)} tetrahedra, min {angle.min():.2f}°, mean {angle.mean():.2f}°, "
          f"{(angle < args.below).sum()} below {args.below}°, {(angle < 8).sum()} below 8°")
    for t in np.argsort(angle)[: (angle < args.below).sum()]:
        v = tets[t]
        edges = [np.linalg.norm(points[v[i]] - points[v[j]]) for i in range(4) for j in range(i + 1, 4)]
        faces = []
        for skip in range(4):
            f = [v[i] for i in range(4) if i != skip]
            mark = "S" if tuple(sorted(f)) in sheet_faces else "-"
            faces.append(f"{mark}{widest_corner(points[f]):.0f}")
        c = points[v].mean(axis=0)
        print(f"  {angle[t]:6.2f}°  edges {min(edges):5.1f}..{max(edges):5.1f}  "
              f"corners on sheets {on_sheet[v].sum()}  faces {' '.join(faces)}  "
              f"at ({c[0]:.1f}, {c[1]:.1f}, {c[2]:.1f})")


if __name__ == "__main__":
    main()
