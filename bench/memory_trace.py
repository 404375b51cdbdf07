#!/usr/bin/python3
"""Runs a command and follows its memory: the resident set sampled every half second, tagged
with the stage the command's progress lines (on stderr) last named. Prints the peak, the
stage it fell in and each stage's own peak and time, as a table and as JSON (--json FILE).

Usage: bench/memory_trace.py [--json FILE] [--every SECONDS] -- COMMAND ARGS...
"""
import json
import os
import re
import subprocess
import sys
import threading
import time


def rss_kb(pid):
    """The resident set of `pid` and its children, in KiB (0 once it is gone)."""
    total = 0
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1])
    except OSError:
        return 0
    return total


def trace(cmd, every=0.5):
    start = time.monotonic()
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.PIPE)
    stage = ["start", ""]
    lines = []
    samples = []  # (seconds, kib, stage)

    def read_stderr():
        for raw in proc.stderr:
            line = raw.decode(errors="replace").rstrip()
            lines.append(line)
            # The progress lines name the stage: "stage 3/9 detect  42%".
            m = re.search(r"stage \d+/\d+ (\S+)\s*(\d+%)?", line)
            if m:
                stage[0] = m.group(1)
                stage[1] = m.group(2) or ""

    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    out = []
    out_reader = threading.Thread(target=lambda: out.append(proc.stdout.read()), daemon=True)
    out_reader.start()
    while proc.poll() is None:
        samples.append((time.monotonic() - start, rss_kb(proc.pid), stage[0], stage[1]))
        time.sleep(every)
    reader.join()
    out_reader.join()
    wall = time.monotonic() - start
    per_stage = {}
    for t, kb, s, _ in samples:
        p = per_stage.setdefault(s, {"first": t, "last": t, "peak_kib": 0})
        p["last"] = t
        p["peak_kib"] = max(p["peak_kib"], kb)
    peak = max(samples, key=lambda s: s[1]) if samples else (0, 0, "", "")
    return {
        "command": cmd,
        "exit_code": proc.returncode,
        "wall_seconds": wall,
        "peak_kib": peak[1],
        "peak_stage": (peak[2] + " " + peak[3]).strip(),
        "peak_at_seconds": peak[0],
        "stages": per_stage,
        "stdout": (out[0] if out else b"").decode(errors="replace"),
        "stderr_tail": lines[-5:],
        # (seconds, KiB, stage, its last percentage), every sample
        "samples": samples,
    }


def main(argv):
    json_path = None
    every = 0.5
    while argv and argv[0] != "--":
        if argv[0] == "--json":
            json_path = argv[1]
            argv = argv[2:]
        elif argv[0] == "--every":
            every = float(argv[1])
            argv = argv[2:]
        else:
            sys.exit(__doc__)
    if not argv:
        sys.exit(__doc__)
    r = trace(argv[1:], every)
    print("exit %d, wall %.1f s, peak %.2f GiB (%.2f GB) in stage %s at %.0f s" %
          (r["exit_code"], r["wall_seconds"], r["peak_kib"] / 2**20, r["peak_kib"] * 1024 / 1e9,
           r["peak_stage"], r["peak_at_seconds"]))
    for s, p in r["stages"].items():
        print("  %-16s %7.1f s .. %7.1f s  peak %.2f GiB" %
              (s, p["first"], p["last"], p["peak_kib"] / 2**20))
    if r["exit_code"] != 0:
        print("\n".join(r["stderr_tail"]))
    if json_path:
        with open(json_path, "w") as f:
            json.dump(r, f, indent=1)
    return r["exit_code"]


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
