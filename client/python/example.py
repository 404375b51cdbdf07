#!/usr/bin/python3
"""Mesh one volume through a sheetmesh server and print what came back.

    /usr/bin/python3 client/python/example.py VOLUME OUT_DIR [--server 127.0.0.1:50051] [--r 5]
        [--extract] [--volume-mesh] [--reference] [--dims NXxNYxNZ] [--token TOKEN]

Uploads the volume (or names it on the server's storage with --reference), runs a job,
prints its stages as they go, downloads the meshes and the report into OUT_DIR and prints
the similarity score.
"""

import argparse
import json
import pathlib
import sys

import grpc

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from sheetmesh_client import SheetmeshClient, SheetmeshError, progress_printer  # noqa: E402
from sheetmesh.v1.parameters_pb2 import VolumeFormat  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("volume")
    ap.add_argument("out_dir")
    ap.add_argument("--server", default="127.0.0.1:50051")
    ap.add_argument("--token", default=None)
    ap.add_argument("--r", type=float, default=None, help="SCVD cell radius in voxels (server default 7)")
    ap.add_argument("--extract", action="store_true", help="run the feature extraction first")
    ap.add_argument("--volume-mesh", action="store_true", help="also make the TetGen volume mesh")
    ap.add_argument("--reference", action="store_true", help="name the volume by its path on the server")
    ap.add_argument("--dims", default=None, help="raw volumes: NXxNYxNZ (default: from a name like a_64x64x32_u8.raw)")
    args = ap.parse_args()

    volume_format = None
    if args.dims:
        volume_format = VolumeFormat(format="raw", dims=[int(n) for n in args.dims.lower().split("x")])

    parameters = {}
    if args.r is not None:
        parameters["r"] = args.r
    if args.extract:
        parameters["extract"] = True
    if args.volume_mesh:
        parameters["volume_mesh"] = True

    client = SheetmeshClient(args.server, token=args.token)
    try:
        job = client.mesh(args.volume, args.out_dir, reference=args.reference,
                          on_update=progress_printer(sys.stdout),
                          volume_format=volume_format, **parameters)
    except grpc.RpcError as e:
        print("error: %s: %s" % (e.code().name, e.details()), file=sys.stderr)
        if client.hint(e):
            print(client.hint(e), file=sys.stderr)
        return 1
    except SheetmeshError as e:
        print("error: %s" % e, file=sys.stderr)
        return 1
    finally:
        client.close()
    for a in job.artifacts:
        print("  %-28s %10d bytes  %s" % (a.name, a.digest.size_bytes, a.media_type))
    report = json.loads((pathlib.Path(args.out_dir) / "report.json").read_text())
    sim = report.get("similarity", {})
    print("similarity %.4f, %s triangles%s" % (
        sim.get("similarity", float("nan")), report.get("surface", {}).get("triangles", "?"),
        " (cached from %s)" % job.cached_from if job.cached_from else ""))
    print("results in %s" % pathlib.Path(args.out_dir).resolve())
    return 0


if __name__ == "__main__":
    sys.exit(main())
