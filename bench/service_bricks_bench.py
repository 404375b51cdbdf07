#!/usr/bin/python3
"""A job run as bricks on the service's queue against the same job in one process (issue 47):
one sheetmesh-server (--local_workers=false) and 1, 2, 3 remote sheetmesh-workers, each
volume named on the shared root; for each worker count the one-process job, then the job
with --bricks: wall time from create to SUCCEEDED, the plan's time, the bricks' span and
each brick task's wall time, the merge's time, the peak memory of every job child (sampled
from /proc while it runs: VmHWM), the bytes the bricks stored, and whether the two
surface.ply are the same bytes. `cat` of the file in the same run gives the scale.

Usage: /usr/bin/python3 bench/service_bricks_bench.py BUILD VOLUME... [--bricks=auto]
       [--workers=1,2,3] [--upload] [--json=FILE] [-- parameters as JSON]
With --upload the volume is uploaded and the workers read the bricked job's input from the
server instead of the shared root (a raw or NRRD volume: the bytes of the bricks each runs;
other formats: one whole copy each), and the bytes each fetched are reported; the
one-process job still names the file, so that no worker holds the upload whole before.
Default parameters: {"labels": [255], "r": 15, "output_previews": false,
                     "similarity_hausdorff": false}
"""
import json
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))
from scaleout_bench import Stack  # noqa: E402


class ChildPeaks:
    """Peak resident memory of each job child, by its job id, sampled every 50 ms."""

    def __init__(self):
        self.peaks, self.stop = {}, threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self):
        while not self.stop.is_set():
            for pid in os.listdir("/proc"):
                if not pid.isdigit():
                    continue
                try:
                    cmd = open("/proc/%s/cmdline" % pid, "rb").read().split(b"\0")
                    if len(cmd) < 3 or cmd[1] != b"--sheetmesh-job-child":
                        continue
                    job = re.search(rb"jobs-([0-9a-f-]+)", cmd[2])
                    status = open("/proc/%s/status" % pid).read()
                    hwm = int(re.search(r"VmHWM:\s+(\d+) kB", status).group(1)) / 1024.0
                except (OSError, AttributeError):
                    continue
                if job:
                    key = "jobs/" + job.group(1).decode()
                    self.peaks[key] = max(self.peaks.get(key, 0), hwm)
            time.sleep(0.05)

    def close(self):
        self.stop.set()
        self.thread.join()


def seconds(a, b):
    return (b.ToNanoseconds() - a.ToNanoseconds()) / 1e9


def bricks_json(client, job, tmp):
    """The merge's account of the bricks (the tasks let their files go once merged)."""
    art = next(a for a in job.artifacts if a.name == "bricks.json")
    client.download(art.digest, str(tmp / "bricks.json"))
    return json.load(open(tmp / "bricks.json"))


def fetched_bytes(scratch, digest):
    """What a worker holds of the upload: the whole file, or the ranges its listing names."""
    cache = scratch / "cache"
    if (cache / digest.hash).exists():
        return digest.size_bytes
    listing = cache / (digest.hash + ".ranges")
    if not listing.exists():
        return 0
    return sum(int(line.split()[1]) for line in listing.read_text().splitlines() if line.strip())


def run_job(client, jobs_pb2, vol, params, bricks="", digest=None):
    t = time.monotonic()
    if digest is not None:
        job = client.create_job(volume_digest=digest, file_name=vol.name, parameters=params, no_cache=True,
                                bricks=bricks)
    else:
        job = client.create_job(volume_path=str(vol), parameters=params, no_cache=True, bricks=bricks)
    done = client.watch(job.name)
    if done.state != jobs_pb2.SUCCEEDED:
        raise RuntimeError("%s: %s" % (job.name, done.error.message))
    return done, time.monotonic() - t


def main(argv):
    params = {"labels": [255], "r": 15, "output_previews": False, "similarity_hausdorff": False}
    if "--" in argv:
        i = argv.index("--")
        params = json.loads(" ".join(argv[i + 1:]))
        argv = argv[:i]
    opts = {a.split("=")[0]: (a.split("=", 1)[1] if "=" in a else "1") for a in argv if a.startswith("--")}
    args = [a for a in argv if not a.startswith("--")]
    if len(args) < 2:
        sys.exit(__doc__)
    build = pathlib.Path(args[0]).resolve()
    sys.path.insert(0, str(ROOT / "client/python"))
    os.environ.setdefault("SHEETMESH_PYTHON_STUBS", str(build / "python"))
    from sheetmesh_client import SheetmeshClient  # finds the stubs
    from sheetmesh.v1 import jobs_pb2
    workers = [int(w) for w in opts.get("--workers", "1,2,3").split(",")]
    bricks = opts.get("--bricks", "auto")
    results = []
    for vol in map(pathlib.Path, args[1:]):
        vol = vol.resolve()
        t = time.monotonic()
        subprocess.run(["cat", str(vol)], stdout=subprocess.DEVNULL, check=True)
        cat = time.monotonic() - t
        for n in workers:
            tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_bricks_bench_"))
            stack = Stack(build, tmp, vol.parent, ["--local_workers=false"], workers=n)
            peaks = ChildPeaks()
            try:
                client = SheetmeshClient(stack.address)
                # --upload: the volume uploaded, each worker reading it from the server.
                digest = client.upload(str(vol)) if "--upload" in opts else None
                one, one_s = run_job(client, jobs_pb2, vol, params)
                split, split_s = run_job(client, jobs_pb2, vol, params, bricks, digest)
                tasks = [client.get_job(t) for t in split.bricks.tasks]
                starts = [t.start_time for t in tasks]
                ends = [t.end_time for t in tasks]
                first = min(starts, key=lambda x: x.ToNanoseconds())
                last = max(ends, key=lambda x: x.ToNanoseconds())
                brick_s = sorted(seconds(t.start_time, t.end_time) for t in tasks)
                r = {
                    "volume": vol.name, "voxels": vol.stat().st_size, "workers": n, "bricks": len(tasks),
                    "input": "upload" if digest is not None else "path",
                    "brick_size": bricks, "cat_s": round(cat, 2), "one_process_s": round(one_s, 1),
                    "bricked_s": round(split_s, 1),
                    "plan_s": round(seconds(split.create_time, first), 2),
                    "bricks_span_s": round(seconds(first, last), 2),
                    "brick_task_s": [round(brick_s[0], 2), round(brick_s[len(brick_s) // 2], 2),
                                     round(brick_s[-1], 2)],
                    "merge_s": round(seconds(last, split.end_time), 1),
                    "brick_bytes": bricks_json(client, split, tmp)["brick_bytes"],
                    "one_process_peak_mib": round(peaks.peaks.get(one.name, 0)),
                    "brick_peak_mib": round(max(peaks.peaks.get(t.name, 0) for t in tasks)),
                    "merge_peak_mib": round(peaks.peaks.get(split.name, 0)),
                    "same_surface": {a.name: a.digest.hash for a in one.artifacts}["surface.ply"]
                    == {a.name: a.digest.hash for a in split.artifacts}["surface.ply"],
                }
                if digest is not None:
                    r["fetched_bytes_per_worker"] = [fetched_bytes(tmp / ("w%d" % i), digest) for i in range(n)]
                    r["upload_bytes"] = digest.size_bytes
                print(json.dumps(r), flush=True)
                results.append(r)
                client.close()
            finally:
                peaks.close()
                stack.close()
                subprocess.run(["rm", "-rf", str(tmp)])
    if "--json" in opts:
        json.dump(results, open(opts["--json"], "w"), indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
