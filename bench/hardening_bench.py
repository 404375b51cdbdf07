#!/usr/bin/python3
"""Hardening benchmarks (issue 19): what isolation costs, what bad headers cost, whether
jobs survive SIGKILLs, and how the server holds under many clients and watchers.

    /usr/bin/python3 bench/hardening_bench.py BUILD overhead [--old OLD_BUILD] [--runs 9]
    /usr/bin/python3 bench/hardening_bench.py BUILD bombs [--old OLD_BUILD]
    /usr/bin/python3 bench/hardening_bench.py BUILD soak [--cycles 100]
    /usr/bin/python3 bench/hardening_bench.py BUILD load [--clients 64 --watchers 256]

OLD_BUILD is a build of an earlier version (e.g. 0.8.0) measured in the same run. Servers
run on loopback with their own data folders under bench/out/hardening.
"""

import argparse
import hashlib
import os
import pathlib
import random
import signal
import statistics
import struct
import subprocess
import sys
import threading
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import service_bench  # noqa: E402
from service_bench import RssSampler, Server, rss_mib, timed  # noqa: E402

service_bench.OUT = service_bench.ROOT / "out" / "hardening"


def pipeline(build):
    return str(build / "worker" / "pipeline" / "sheetmesh-pipeline")


def sample(build, folder):
    vol = folder / "sample_128x112x96_u8.raw"
    subprocess.run([pipeline(build), "phantom", "--preset=sample", "-o", str(vol)], check=True,
                   stdout=subprocess.DEVNULL)
    return vol


def threads_of(pid):
    try:
        for line in open("/proc/%d/status" % pid):
            if line.startswith("Threads:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


# ------------------------------------------------------------------------------------------
# The child process per job: latency on the sample against the in-thread run and 0.8.0.

def bench_overhead(build, old, runs):
    rows = []
    setups = [("this build, each job in a child process", build, [])]
    setups.append(("this build, --isolate_jobs=false (in a thread)", build, ["--isolate_jobs=false"]))
    if old:
        setups.append(("0.8.0 (in a thread)", old, []))
    for label, b, flags in setups:
        server = Server(b, "overhead", "--workers=1", *flags)
        vol = sample(build, server.dir / "root")
        server.cli("mesh", str(vol), "--reference", "--no_cache", "-o", str(server.dir / "warm"))
        times = [timed(lambda: server.cli("mesh", str(vol), "--reference", "--no_cache",
                                          "-o", str(server.dir / ("o%d" % i))))
                 for i in range(runs)]
        server.stop()
        rows.append((label, statistics.median(times), min(times), max(times)))
    offline = statistics.median(
        timed(lambda: subprocess.run([pipeline(build), "surface", str(vol), "-o", str(vol.parent / "off")],
                                     check=True, stdout=subprocess.DEVNULL)) for _ in range(runs))
    print("job latency on the sample (sheetmesh mesh --reference --no_cache), %d runs" % runs)
    for label, med, lo, hi in rows:
        print("  %-50s median %.3f s (%.3f-%.3f)" % (label, med, lo, hi))
    print("  %-50s median %.3f s" % ("offline sheetmesh-pipeline surface", offline))
    print("  child process overhead: %+.3f s per job" % (rows[0][1] - rows[1][1]))


# ------------------------------------------------------------------------------------------
# Header bombs: the reader's peak memory and answer, against 0.8.0's.

def tiff_claiming(side, path, deflate=False):
    entries = [(256, 4, side), (257, 4, side), (258, 3, 8), (259, 3, 8 if deflate else 1), (262, 3, 1),
               (273, 4, 8 + 2 + 9 * 12 + 4), (277, 3, 1), (278, 4, side), (279, 4, 17000)]
    out = b"II" + struct.pack("<HI", 42, 8) + struct.pack("<H", len(entries))
    for tag, typ, val in entries:
        out += struct.pack("<HHI", tag, typ, 1)
        out += struct.pack("<HH", val, 0) if typ == 3 else struct.pack("<I", val)
    path.write_bytes(out + struct.pack("<I", 0) + bytes(17000))
    return path


def bench_bombs(build, old):
    folder = service_bench.OUT / "bombs"
    folder.mkdir(parents=True, exist_ok=True)
    vol = sample(build, folder)
    subprocess.run([pipeline(build), "convert", str(vol), "-o", str(folder / "s.vdb"), "--out_format=vdb"],
                   check=True, stdout=subprocess.DEVNULL)
    data = (folder / "s.vdb").read_bytes()
    (folder / "cut.vdb").write_bytes(data[:40000])
    (folder / "huge.nrrd").write_bytes(
        b"NRRD0004\ntype: float\ndimension: 3\nsizes: 100000 100000 100000\nencoding: raw\n\nxxxx")
    files = [("the sample (1.4 MB, for scale)", vol),
             ("TIFF claiming 60000^2, 17 KB", tiff_claiming(60000, folder / "b60000.tif")),
             ("TIFF claiming 60000^2, deflate, 17 KB", tiff_claiming(60000, folder / "b60000z.tif", True)),
             ("TIFF claiming 200000^2, 17 KB", tiff_claiming(200000, folder / "b200000.tif")),
             ("NRRD claiming 100000^3 float, 90 B", folder / "huge.nrrd"),
             ("VDB cut to 40000 bytes", folder / "cut.vdb")]
    builds = [("this build", build)] + ([("0.8.0", old)] if old else [])
    print("peak memory of `sheetmesh-pipeline info FILE` (GNU time's maximum RSS)")
    for label, path in files:
        line = "  %-40s" % label
        for name, b in builds:
            r = subprocess.run(["/usr/bin/time", "-f", "%M %e", pipeline(b), "info", str(path)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            kib, secs = r.stderr.strip().splitlines()[-1].split()[-2:]
            line += "  %s: exit %3d, %7.0f MiB, %5.2f s" % (name, r.returncode, int(kib) / 1024, float(secs))
        print(line)


# ------------------------------------------------------------------------------------------
# Durability: SIGKILL the server at random moments; every accepted job is accounted for.

def grpc_client(build, address):
    os.environ["SHEETMESH_PYTHON_STUBS"] = str(build / "python")
    sys.path.insert(0, str(service_bench.ROOT.parent / "client" / "python"))
    import sheetmesh_client  # noqa: E402
    return sheetmesh_client


def bench_soak(build, cycles, seed):
    rng = random.Random(seed)
    name = "soak"
    first = Server(build, name, "--workers=2", "--lease_seconds=3")
    folder = first.dir
    vols = []
    for i in range(3):
        v = folder / "root" / ("soak%d_48x48x48_u8.raw" % i)
        subprocess.run([pipeline(build), "phantom", "--dims=48x48x48", "--seed=%d" % (7 + i), "-o", str(v)],
                       check=True, stdout=subprocess.DEVNULL)
        vols.append(v)
    first.stop()
    sc = grpc_client(build, None)
    from sheetmesh.v1 import jobs_pb2  # noqa: E402
    accepted = {}  # request id -> job name
    kills = 0
    server_bin = str(build / "server" / "sheetmesh-server")

    def start():
        port_file = folder / "port"
        if port_file.exists():
            port_file.unlink()
        proc = subprocess.Popen([server_bin, "--address=127.0.0.1:0", "--data_dir=%s" % (folder / "data"),
                                 "--port_file=%s" % port_file, "--allowed_root=%s" % (folder / "root"),
                                 "--workers=2", "--lease_seconds=3", "--max_attempts=1000"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        while not (port_file.exists() and port_file.read_text().endswith("\n")):
            time.sleep(0.01)
        return proc, "127.0.0.1:" + port_file.read_text().strip()

    t0 = time.perf_counter()
    for cycle in range(cycles):
        proc, address = start()
        client = sc.SheetmeshClient(address)
        stop = threading.Event()

        def submit():
            k = 0
            while not stop.is_set():
                rid = "soak-%d-%d" % (cycle, k)
                k += 1
                try:
                    if rng.random() < 0.3:  # an upload now and then, killed mid-stream sometimes
                        digest = client.upload(str(vols[k % 3]))
                        job = client.create_job(volume_digest=digest, file_name=vols[k % 3].name,
                                                request_id=rid, no_cache=True)
                    else:
                        job = client.create_job(volume_path=str(vols[k % 3]), request_id=rid, no_cache=True)
                    accepted[rid] = job.name
                except Exception:
                    return  # the server died under the call: not accepted (or retried below)
                time.sleep(rng.uniform(0, 0.2))

        t = threading.Thread(target=submit, daemon=True)
        t.start()
        time.sleep(rng.uniform(0.2, 2.0))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        kills += 1
        stop.set()
        t.join(timeout=10)
        client.close()
    # Every accepted job: exactly one job per request id, finished, artifacts intact.
    proc, address = start()
    client = sc.SheetmeshClient(address)
    pending = set(accepted.values())
    deadline = time.time() + 900
    final = {}
    while pending and time.time() < deadline:
        for name in list(pending):
            job = client.get_job(name)
            if job.state in (jobs_pb2.SUCCEEDED, jobs_pb2.FAILED, jobs_pb2.CANCELLED):
                final[name] = job
                pending.discard(name)
        time.sleep(0.5)
    listed = []
    token = ""
    while True:
        resp = client.jobs.ListJobs(jobs_pb2.ListJobsRequest(page_size=1000, page_token=token),
                                     metadata=client._metadata)
        listed.extend(resp.jobs)
        token = resp.next_page_token
        if not token:
            break
    by_rid = {}
    for j in listed:
        by_rid.setdefault(j.request_id, []).append(j.name)
    duplicated = sum(1 for rid in accepted if len(by_rid.get(rid, [])) > 1)
    lost = sum(1 for rid, name in accepted.items() if name not in by_rid.get(rid, []))
    states = {}
    for job in final.values():
        states[jobs_pb2.JobState.Name(job.state)] = states.get(jobs_pb2.JobState.Name(job.state), 0) + 1
    checked = bad = 0
    for job in final.values():
        for a in job.artifacts:
            path = folder / "check.bin"
            client.download(a.digest, str(path))
            checked += 1
            bad += hashlib.sha256(path.read_bytes()).hexdigest() != a.digest.hash
    attempts = [job.attempts for job in final.values()]
    client.close()
    proc.terminate()
    proc.wait()
    print("durability soak: %d SIGKILLs at random moments (0.2-2 s into each run), %.0f s" % (
        kills, time.perf_counter() - t0))
    print("  accepted jobs %d; finished %d (%s); unfinished %d; lost %d; duplicated %d" % (
        len(accepted), len(final), ", ".join("%s %d" % kv for kv in sorted(states.items())), len(pending),
        lost, duplicated))
    print("  runs per job: median %d, max %d; artifacts downloaded and digest-checked %d, bad %d" % (
        statistics.median(attempts) if attempts else 0, max(attempts) if attempts else 0, checked, bad))


# ------------------------------------------------------------------------------------------
# Load: many clients create jobs while many watchers follow them.

def bench_load(build, clients, watchers, jobs_each):
    server = Server(build, "load")
    sc = grpc_client(build, None)
    from sheetmesh.v1 import jobs_pb2  # noqa: E402
    vols = []
    for i in range(4):
        v = server.dir / "root" / ("load%d_64x64x64_u8.raw" % i)
        subprocess.run([pipeline(build), "phantom", "--dims=64x64x64", "--seed=%d" % (30 + i), "-o", str(v)],
                       check=True, stdout=subprocess.DEVNULL)
        vols.append(v)
    names, errors, lock = [], [], threading.Lock()
    watched = {"ended": 0, "messages": 0, "errors": 0}
    created = threading.Event()

    def client_thread(c):
        with sc.SheetmeshClient(server.address) as cl:
            for j in range(jobs_each):
                try:
                    job = cl.create_job(volume_path=str(vols[(c + j) % 4]), request_id="load-%d-%d" % (c, j),
                                        no_cache=True)
                    with lock:
                        names.append(job.name)
                        if len(names) == clients * jobs_each:
                            created.set()
                except Exception as e:  # noqa: BLE001
                    with lock:
                        errors.append(str(e))

    def watcher_thread(w):
        created.wait(120)
        with sc.SheetmeshClient(server.address) as cl:
            name = names[w % len(names)]
            n = [0]
            try:
                job = cl.watch(name, on_update=lambda job, heartbeat: n.__setitem__(0, n[0] + 1))
                with lock:
                    watched["ended"] += job.state == jobs_pb2.SUCCEEDED
                    watched["messages"] += n[0]
            except Exception:  # noqa: BLE001
                with lock:
                    watched["errors"] += 1

    base, threads0 = rss_mib(server.proc.pid), threads_of(server.proc.pid)
    peak_threads = [threads0]
    stop = threading.Event()

    def sample_threads():
        while not stop.is_set():
            peak_threads[0] = max(peak_threads[0], threads_of(server.proc.pid))
            time.sleep(0.05)

    st = threading.Thread(target=sample_threads, daemon=True)
    st.start()
    with RssSampler(server.proc.pid) as s:
        t0 = time.perf_counter()
        ts = [threading.Thread(target=client_thread, args=(c,)) for c in range(clients)]
        ts += [threading.Thread(target=watcher_thread, args=(w,)) for w in range(watchers)]
        for t in ts:
            t.start()
        for t in ts:
            t.join()
        wall = time.perf_counter() - t0
    stop.set()
    after = rss_mib(server.proc.pid)
    server.stop()
    print("load: %d clients x %d jobs (64^3 phantoms by reference, --no_cache) and %d watchers" % (
        clients, jobs_each, watchers))
    print("  jobs created %d, client errors %d; watches ended SUCCEEDED %d of %d, watch errors %d, %d messages" % (
        len(names), len(errors), watched["ended"], watchers, watched["errors"], watched["messages"]))
    print("  wall %.1f s; server RSS %.0f MiB before, peak %.0f, after %.0f; server threads %d before, peak %d" % (
        wall, base, max(s.samples), after, threads0, peak_threads[0]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", type=pathlib.Path)
    ap.add_argument("what", choices=["overhead", "bombs", "soak", "load"])
    ap.add_argument("--old", type=pathlib.Path)
    ap.add_argument("--runs", type=int, default=9)
    ap.add_argument("--cycles", type=int, default=100)
    ap.add_argument("--seed", type=int, default=19)
    ap.add_argument("--clients", type=int, default=64)
    ap.add_argument("--watchers", type=int, default=256)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    build = a.build.resolve()
    old = a.old.resolve() if a.old else None
    if a.what == "overhead":
        bench_overhead(build, old, a.runs)
    elif a.what == "bombs":
        bench_bombs(build, old)
    elif a.what == "soak":
        bench_soak(build, a.cycles, a.seed)
    else:
        bench_load(build, a.clients, a.watchers, a.jobs)


if __name__ == "__main__":
    main()
