#!/usr/bin/python3
"""Scale-out: jobs per minute with the embedded default against remote sheetmesh-workers,
the time from a worker's death to its job running elsewhere, and leasing latency under
8 leasers on PostgreSQL against SQLite.

- throughput: --jobs jobs on the sample (`phantom --preset=sample`, r = 7, no cache) at
  once; (a) the embedded default (one server, its in-process workers, one per core),
  (b) a server with --local_workers=false and one sheetmesh-worker, (c) two workers. Jobs
  per minute from the first create to the last end.
- failover: a job on a worker that is SIGKILLed while it runs; seconds from the kill to
  the job RUNNING again on the other worker, with --lease_seconds 3 and 10.
- leasing: --lease_jobs queued jobs (no workers), 8 threads calling WorkerService.LeaseJob
  then FinishJob until none is left; each LeaseJob's latency, on SQLite and on PostgreSQL
  (a cluster of tools/pg_cluster.sh).

Usage: /usr/bin/python3 bench/scaleout_bench.py [BUILD_DIR] [--jobs 12] [--lease_jobs 400]
"""
import argparse
import os
import pathlib
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "client/python"))
sys.path.insert(0, str(ROOT / "tests/testing"))
from ports import wait_port_file  # noqa: E402


class Stack:
    def __init__(self, build, tmp, root, server_flags=(), workers=0, worker_flags=()):
        self.build, self.tmp, self.procs = build, tmp, []
        tmp.mkdir(parents=True, exist_ok=True)
        (tmp / "wtoken").write_text("bench-worker-token\n")
        self.server = self.start([str(build / "server/sheetmesh-server"), "--address=127.0.0.1:0",
                                  "--data_dir=%s" % (tmp / "data"), "--port_file=%s" % (tmp / "port"),
                                  "--allowed_root=%s" % root, "--worker_token_file=%s" % (tmp / "wtoken")]
                                 + list(server_flags))
        self.address = "127.0.0.1:%d" % wait_port_file(tmp / "port", self.server, "sheetmesh-server")
        self.workers = [self.start_worker(i, root, worker_flags) for i in range(workers)]

    def start(self, cmd):
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.procs.append(p)
        return p

    def start_worker(self, i, root, flags=()):
        return self.start([str(self.build / "worker/remote/sheetmesh-worker"), "--server=%s" % self.address,
                           "--token_file=%s" % (self.tmp / "wtoken"), "--scratch_dir=%s" % (self.tmp / ("w%d" % i)),
                           "--allowed_root=%s" % root, "--workers=1", "--renew_seconds=1"] + list(flags))

    def close(self):
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
                p.wait(timeout=60)


def run_jobs(client, jobs_pb2, sample, n):
    t = time.perf_counter()
    names = [client.create_job(volume_path=str(sample), parameters={"r": 7, "labels": [255]}, no_cache=True).name
             for _ in range(n)]
    for name in names:
        job = client.watch(name)
        assert job.state == jobs_pb2.SUCCEEDED, job.error.message
    return 60.0 * n / (time.perf_counter() - t)


def wait(client, name, pred, timeout=300):
    deadline = time.time() + timeout
    while True:
        j = client.get_job(name)
        if pred(j):
            return j
        if time.time() > deadline:
            raise RuntimeError("timed out on %s" % name)
        time.sleep(0.02)


def failover(build, tmp, root, slow, lease, jobs_pb2):
    from sheetmesh_client import SheetmeshClient
    stack = Stack(build, tmp / ("failover%d" % lease), root, ["--local_workers=false", "--lease_seconds=%d" % lease],
                  workers=1)
    try:
        client = SheetmeshClient(stack.address)
        job = client.create_job(volume_path=str(slow), parameters={"extract": True}, no_cache=True)
        wait(client, job.name, lambda j: j.state == jobs_pb2.RUNNING)
        other = stack.start_worker(9, root)
        time.sleep(1)
        stack.workers[0].send_signal(signal.SIGKILL)
        t = time.perf_counter()
        wait(client, job.name, lambda j: j.state == jobs_pb2.RUNNING and j.attempts == 2)
        took = time.perf_counter() - t
        client.cancel_job(job.name)
        client.close()
        del other
        return took
    finally:
        stack.close()


def cancel_latency(build, tmp, root, slow, jobs_pb2, runs=5):
    """Seconds from CancelJob to CANCELLED for a job a remote sheetmesh-worker runs (the
    cancel reaches it through the job store and its lease): each of `runs` jobs cancelled
    a second into its run."""
    from sheetmesh_client import SheetmeshClient
    stack = Stack(build, tmp / "cancel", root, ["--local_workers=false"], workers=1)
    took = []
    try:
        client = SheetmeshClient(stack.address)
        for _ in range(runs):
            job = client.create_job(volume_path=str(slow), parameters={"extract": True}, no_cache=True)
            wait(client, job.name, lambda j: j.state == jobs_pb2.RUNNING)
            time.sleep(1)
            t = time.perf_counter()
            client.cancel_job(job.name)
            wait(client, job.name, lambda j: j.state == jobs_pb2.CANCELLED)
            took.append(time.perf_counter() - t)
        client.close()
        return took
    finally:
        stack.close()


def leasing(build, tmp, root, sample, n, postgres, jobs_pb2):
    import grpc
    from sheetmesh_client import SheetmeshClient
    from sheetmesh.v1 import workers_pb2, workers_pb2_grpc
    flags = ["--local_workers=false"] + (["--postgres=%s" % postgres] if postgres else [])
    stack = Stack(build, tmp / ("lease_pg" if postgres else "lease_sqlite"), root, flags)
    try:
        client = SheetmeshClient(stack.address)
        for i in range(n):
            client.create_job(volume_path=str(sample), parameters={"r": 7 + i * 1e-6}, no_cache=True)
        client.close()
        latencies, lock = [], threading.Lock()
        md = [("authorization", "Bearer bench-worker-token")]

        def leaser(k):
            ch = grpc.insecure_channel(stack.address)
            stub = workers_pb2_grpc.WorkerServiceStub(ch)
            mine = []
            while True:
                t = time.perf_counter()
                r = stub.LeaseJob(workers_pb2.LeaseJobRequest(worker="bench-%d" % k), metadata=md)
                mine.append(time.perf_counter() - t)
                if not r.HasField("job"):
                    break
                stub.FinishJob(workers_pb2.FinishJobRequest(name=r.job.name, worker="bench-%d" % k,
                                                            state=jobs_pb2.FAILED), metadata=md)
            with lock:
                latencies.extend(mine)
            ch.close()

        t = time.perf_counter()
        threads = [threading.Thread(target=leaser, args=(k,)) for k in range(8)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        wall = time.perf_counter() - t
        latencies.sort()
        return (statistics.median(latencies) * 1e3, latencies[int(0.95 * len(latencies))] * 1e3, n / wall)
    finally:
        stack.close()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=str(ROOT / "build"))
    ap.add_argument("--jobs", type=int, default=12)
    ap.add_argument("--lease_jobs", type=int, default=400)
    ap.add_argument("--only", default="", help="throughput, failover, cancel, leasing (comma-separated; default all)")
    a = ap.parse_args()
    parts = set(a.only.split(",")) if a.only else {"throughput", "failover", "cancel", "leasing"}
    build = pathlib.Path(a.build).resolve()
    sys.path.insert(0, str(build / "python"))
    os.environ.setdefault("SHEETMESH_PYTHON_STUBS", str(build / "python"))
    from sheetmesh_client import SheetmeshClient
    from sheetmesh.v1 import jobs_pb2
    (ROOT / "bench/out").mkdir(exist_ok=True)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_scaleout_", dir=str(ROOT / "bench/out")))
    tmp.chmod(0o755)
    root = tmp / "root"
    root.mkdir()
    sample = root / "rock_128x112x96_u8.raw"
    slow = root / "slow_384x384x384_u8.raw"
    pipeline = str(build / "worker/pipeline/sheetmesh-pipeline")
    subprocess.run([pipeline, "phantom", "--preset=sample", "-o", str(sample)], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([pipeline, "phantom", "--dims=384x384x384", "--seed=14", "-o", str(slow)], check=True,
                   stdout=subprocess.DEVNULL)
    pg = None
    try:
        for label, flags, workers in (("embedded default (in-process, one per core)", [], 0),
                                      ("one sheetmesh-worker", ["--local_workers=false"], 1),
                                      ("two sheetmesh-workers", ["--local_workers=false"], 2)):
            if "throughput" not in parts:
                break
            stack = Stack(build, tmp / label.split()[0], root, flags, workers)
            try:
                client = SheetmeshClient(stack.address)
                rate = run_jobs(client, jobs_pb2, sample, a.jobs)
                client.close()
                print("throughput, %s: %.1f jobs per minute (%d jobs)" % (label, rate, a.jobs))
            finally:
                stack.close()
        for lease in (3, 10) if "failover" in parts else ():
            print("failover, --lease_seconds %d: the killed worker's job RUNNING again %.1f s after the kill"
                  % (lease, failover(build, tmp, root, slow, lease, jobs_pb2)))
        if "cancel" in parts:
            took = sorted(cancel_latency(build, tmp, root, slow, jobs_pb2))
            print("cancel of a job a sheetmesh-worker runs: CANCELLED %.2f s after CancelJob (median of %d; "
                  "%.2f-%.2f s)" % (took[len(took) // 2], len(took), took[0], took[-1]))
        if "leasing" not in parts:
            return
        pg = subprocess.run(["bash", str(ROOT / "tools/pg_cluster.sh"), "start", str(tmp / "pg")], check=True,
                            capture_output=True, text=True).stdout.strip()
        for name, conninfo in (("SQLite", None), ("PostgreSQL", pg)):
            med, p95, rate = leasing(build, tmp, root, sample, a.lease_jobs, conninfo, jobs_pb2)
            print("leasing, 8 leasers on %s: LeaseJob median %.2f ms, p95 %.2f ms; %.0f jobs leased and ended per s"
                  % (name, med, p95, rate))
    finally:
        if pg:
            subprocess.run(["bash", str(ROOT / "tools/pg_cluster.sh"), "stop", str(tmp / "pg")])
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
