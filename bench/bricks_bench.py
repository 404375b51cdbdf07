#!/usr/bin/python3
"""Bricks against one process (issue 47): for each volume, the time of `cat` of the file in
the same run, then plan, the bricks run by 1, 2 and 3 processes at once (wall time, each
brick's time and peak memory, the bytes they write), the merge (time, peak) and, where
asked, the one-process run of the same job, with a byte comparison of the two surfaces.

Each brick runs with --memory_limit_gb=3 (a worker's cap). With --kill, one brick of the last
run is started again and SIGKILLed mid-run: it must leave no file, and run again write the
bytes it wrote before.

Usage: bench/bricks_bench.py BUILD VOLUME... [--brick=512] [--workers=1,2,3] [--one]
       [--merge] [--kill] [--json=FILE] [-- job flags]
Default job flags: --labels=255 --r=15 --output_previews=false --similarity_hausdorff=false
"""
import hashlib
import json
import os
import signal
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor


def timed(cmd, log=None):
    """Runs cmd; returns (seconds, peak RSS in MiB) of it alone."""
    start = time.monotonic()
    out = open(log, "w") if log else subprocess.DEVNULL
    child = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT)
    _, status, usage = os.wait4(child.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError("%s failed (see %s)" % (" ".join(cmd), log))
    return time.monotonic() - start, usage.ru_maxrss / 1024.0


def dir_bytes(path):
    total = 0
    for root, _, files in os.walk(path):
        total += sum(os.path.getsize(os.path.join(root, f)) for f in files)
    return total


def main(argv):
    flags = ["--labels=255", "--r=15", "--output_previews=false",
             "--similarity_hausdorff=false"]
    if "--" in argv:
        i = argv.index("--")
        flags = argv[i + 1:]
        argv = argv[:i]
    opts = {a.split("=")[0]: (a.split("=", 1)[1] if "=" in a else "1")
            for a in argv if a.startswith("--")}
    args = [a for a in argv if not a.startswith("--")]
    if len(args) < 2:
        sys.exit(__doc__)
    cli = os.path.join(args[0], "worker/pipeline/sheetmesh-pipeline")
    workers = [int(w) for w in opts.get("--workers", "1,2,3").split(",")]
    results = []
    for vol in args[1:]:
        work = vol + ".bench"
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        r = {"volume": vol, "bytes": os.path.getsize(vol), "brick": opts.get("--brick", "512")}
        r["cat_seconds"], _ = timed(["sh", "-c", "cat '%s' > /dev/null" % vol])
        plan = os.path.join(work, "plan")
        timed([cli, "plan", vol, "-o", plan, "--brick_size=" + r["brick"]] + flags,
              os.path.join(work, "plan.log"))
        count = len(json.load(open(os.path.join(plan, "plan.json")))["bricks"])
        r["bricks"] = count
        r["runs"] = []
        for w in workers:
            shutil.rmtree(os.path.join(plan, "bricks"))
            os.makedirs(os.path.join(plan, "bricks"))
            start = time.monotonic()
            with ThreadPoolExecutor(max_workers=w) as pool:
                each = list(pool.map(
                    lambda i: timed([cli, "brick", plan, "--index=%d" % i, "--memory_limit_gb=3"],
                                    os.path.join(work, "brick_%d.log" % i)), range(count)))
            wall = time.monotonic() - start
            run = {"workers": w, "wall_seconds": wall,
                   "brick_seconds_max": max(s for s, _ in each),
                   "brick_seconds_mean": sum(s for s, _ in each) / count,
                   "brick_peak_mib_max": max(m for _, m in each),
                   "brick_bytes": dir_bytes(os.path.join(plan, "bricks"))}
            r["runs"].append(run)
            print("%s: %d bricks by %d at once: %.1f s (cat %.1f s); a brick at most %.1f s, "
                  "%.0f MiB; %d bytes" % (vol, count, w, wall, r["cat_seconds"],
                                          run["brick_seconds_max"], run["brick_peak_mib_max"],
                                          run["brick_bytes"]), flush=True)
        if "--kill" in opts:
            i = count // 2
            path = os.path.join(plan, "bricks", "brick_%06d.bin" % i)
            before = hashlib.sha256(open(path, "rb").read()).hexdigest()
            os.remove(path)
            child = subprocess.Popen([cli, "brick", plan, "--index=%d" % i],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            # A third of a brick's time: past its start, short of its end.
            time.sleep(max(0.05, r["runs"][-1]["brick_seconds_mean"] / 3))
            finished = child.poll() is not None
            if not finished:
                child.send_signal(signal.SIGKILL)
            child.wait()
            left = os.path.exists(path) and not finished
            timed([cli, "brick", plan, "--index=%d" % i])
            again = hashlib.sha256(open(path, "rb").read()).hexdigest()
            r["kill"] = {"brick": i, "finished_before_kill": finished, "file_after_kill": left,
                         "same_bytes": again == before}
            print("  brick %d SIGKILLed: %s; run again: %s" %
                  (i, "a file was left" if left else "no file left",
                   "the same bytes" if again == before else "OTHER BYTES"), flush=True)
        if "--merge" in opts:
            merged = os.path.join(work, "merged")
            r["merge_seconds"], r["merge_peak_mib"] = timed(
                [cli, "merge", plan, "-o", merged], os.path.join(work, "merge.log"))
            r["merge_output_bytes"] = dir_bytes(merged)
            print("  merge %.1f s, peak %.0f MiB, wrote %d bytes" %
                  (r["merge_seconds"], r["merge_peak_mib"], r["merge_output_bytes"]), flush=True)
        if "--one" in opts:
            one = os.path.join(work, "one")
            r["one_seconds"], r["one_peak_mib"] = timed(
                [cli, "run", vol, "-o", one] + flags, os.path.join(work, "one.log"))
            print("  one process %.1f s, peak %.0f MiB" % (r["one_seconds"], r["one_peak_mib"]),
                  flush=True)
            if "--merge" in opts:
                same = open(os.path.join(one, "surface.ply"), "rb").read() == open(
                    os.path.join(merged, "surface.ply"), "rb").read()
                r["same_surface"] = same
                print("  the merge's surface.ply is %s one process's" %
                      ("byte for byte" if same else "NOT"), flush=True)
        results.append(r)
    if "--json" in opts:
        with open(opts["--json"], "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
