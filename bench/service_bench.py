#!/usr/bin/python3
"""Service benchmarks: upload throughput, job latency against the offline CLI, and load.

    /usr/bin/python3 bench/service_bench.py BUILD_DIR [upload|latency|load|all] [--gib 1]

Starts a real sheetmesh-server (its own data folder under bench/out/service), drives it
with the `sheetmesh` CLI, samples the server's resident memory from /proc every 50 ms,
and prints the figures bench/RESULTS.md quotes. Timings are compared with something
measured in the same run (reading the file, the offline CLI) because these machines are
noisy.
"""

import argparse
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parent
OUT = ROOT / "out" / "service"


def rss_mib(pid):
    try:
        for line in open("/proc/%d/status" % pid):
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


class RssSampler:
    """Samples a process's RSS in the background: min, max and the series."""

    def __init__(self, pid, period=0.05):
        self.pid, self.period, self.samples = pid, period, []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self._stop.is_set():
            self.samples.append(rss_mib(self.pid))
            time.sleep(self.period)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def server_env():
    """The server's environment: SERVER_GLIBC_TUNABLES, when set, is its GLIBC_TUNABLES."""
    env = dict(os.environ)
    if "SERVER_GLIBC_TUNABLES" in env:
        env["GLIBC_TUNABLES"] = env["SERVER_GLIBC_TUNABLES"]
    return env


class Server:
    def __init__(self, build, name, *flags):
        self.build = build
        self.dir = OUT / name
        shutil.rmtree(self.dir, ignore_errors=True)
        self.dir.mkdir(parents=True)
        (self.dir / "root").mkdir()
        port_file = self.dir / "port"
        self.proc = subprocess.Popen(
            [str(build / "server" / "sheetmesh-server"), "--address=127.0.0.1:0",
             "--data_dir=%s" % (self.dir / "data"), "--port_file=%s" % port_file,
             "--allowed_root=%s" % (self.dir / "root")] + list(flags),
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=server_env())
        while not (port_file.exists() and port_file.read_text().endswith("\n")):
            if self.proc.poll() is not None:
                raise RuntimeError("sheetmesh-server did not start")
            time.sleep(0.02)
        self.address = "127.0.0.1:" + port_file.read_text().strip()

    def cli(self, *args, check=True):
        return subprocess.run([str(self.build / "client" / "sheetmesh"), "--server=" + self.address] + list(args),
                              check=check, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def stop(self):
        self.proc.terminate()
        self.proc.wait(timeout=120)


def timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def drop_cache(path):
    """Asks the kernel to forget a file's pages (so that reads come from the disk)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
    finally:
        os.close(fd)


def bench_upload(build, gib):
    server = Server(build, "upload", "--workers=1")
    path = server.dir / ("volume_%dGiB.bin" % gib)
    size = gib << 30
    with open(path, "wb") as f:  # incompressible, so nothing on the way can cheat
        block = os.urandom(64 << 20)
        for _ in range(size // len(block)):
            f.write(block)
            block = block[1:] + block[:1]
    read = timed(lambda: subprocess.run(["cat", str(path)], stdout=subprocess.DEVNULL, check=True))
    copy_to = server.dir / "copy.bin"
    copy = timed(lambda: subprocess.run(["dd", "if=%s" % path, "of=%s" % copy_to, "bs=4M", "conv=fsync",
                                         "status=none"], check=True))
    copy_to.unlink()
    sha = timed(lambda: subprocess.run(["sha256sum", str(path)], stdout=subprocess.DEVNULL, check=True))
    base = rss_mib(server.proc.pid)
    with RssSampler(server.proc.pid) as s:
        up = timed(lambda: server.cli("upload", str(path)))
    # A second upload of the same file: the client hashes it, the server has it.
    again = timed(lambda: server.cli("upload", str(path)))
    server.stop()
    mb = size / 1e6
    print("upload of %d GiB (%d bytes) over loopback" % (gib, size))
    print("  upload              %6.2f s  %7.1f MB/s  (client hashes the file, then streams it)" % (up, mb / up))
    print("  sha256sum of file   %6.2f s  %7.1f MB/s" % (sha, mb / sha))
    print("  cat (page cache)    %6.2f s  %7.1f MB/s" % (read, mb / read))
    print("  dd + fsync copy     %6.2f s  %7.1f MB/s" % (copy, mb / copy))
    print("  upload again        %6.2f s  (already stored: hash + FindMissing only)" % again)
    q = len(s.samples) // 4 or 1
    quarters = [statistics.median(s.samples[i * q:(i + 1) * q] or [0]) for i in range(4)]
    print("  server RSS          %.0f MiB before, %.0f-%.0f MiB during (%d samples); medians by quarter %s MiB"
          % (base, min(s.samples), max(s.samples), len(s.samples), " / ".join("%.0f" % m for m in quarters)))
    path.unlink()


def bench_latency(build, runs):
    server = Server(build, "latency", "--workers=1")
    vol = server.dir / "root" / "sample_128x112x96_u8.raw"
    subprocess.run([str(build / "worker" / "pipeline" / "sheetmesh-pipeline"), "phantom", "--preset=sample",
                    "-o", str(vol)], check=True, stdout=subprocess.DEVNULL)
    pipeline = str(build / "worker" / "pipeline" / "sheetmesh-pipeline")
    offline, service, reference, cached = [], [], [], []
    for i in range(runs):
        out = server.dir / ("off%d" % i)
        offline.append(timed(lambda: subprocess.run([pipeline, "surface", str(vol), "-o", str(out)],
                                                    check=True, stdout=subprocess.DEVNULL)))
        service.append(timed(lambda: server.cli("mesh", str(vol), "--no_cache", "-o", str(server.dir / ("svc%d" % i)))))
        reference.append(timed(lambda: server.cli("mesh", str(vol), "--reference", "--no_cache",
                                                  "-o", str(server.dir / ("ref%d" % i)))))
        cached.append(timed(lambda: server.cli("mesh", str(vol), "-o", str(server.dir / ("hit%d" % i)))))
    server.stop()
    med = statistics.median
    print("job latency on the sample (128x112x96 u8, 1.4 MB), %d runs, medians" % runs)
    print("  offline CLI surface          %.3f s" % med(offline))
    print("  service mesh (upload)        %.3f s  overhead %+.3f s" % (med(service), med(service) - med(offline)))
    print("  service mesh --reference     %.3f s  overhead %+.3f s" % (med(reference), med(reference) - med(offline)))
    print("  service mesh, cached result  %.3f s" % med(cached))


def bench_load(build, clients, jobs, n):
    server = Server(build, "load")
    pipeline = str(build / "worker" / "pipeline" / "sheetmesh-pipeline")
    vols = []
    for i in range(4):
        v = server.dir / ("load%d_%dx%dx%d_u8.raw" % (i, n, n, n))
        subprocess.run([pipeline, "phantom", "--dims=%dx%dx%d" % (n, n, n), "--seed=%d" % (100 + i), "-o", str(v)],
                       check=True, stdout=subprocess.DEVNULL)
        vols.append(v)
    one = timed(lambda: subprocess.run([pipeline, "surface", str(vols[0]), "-o", str(server.dir / "one")],
                                       check=True, stdout=subprocess.DEVNULL))
    results, latencies, lock = [], [], threading.Lock()

    def client(c):
        for j in range(jobs):
            t = time.perf_counter()
            r = server.cli("mesh", str(vols[(c + j) % 4]), "--no_cache", "-o", str(server.dir / ("c%d_%d" % (c, j))),
                           check=False)
            with lock:
                results.append(r.returncode)
                latencies.append(time.perf_counter() - t)

    base = rss_mib(server.proc.pid)
    with RssSampler(server.proc.pid) as s:
        t0 = time.perf_counter()
        threads = [threading.Thread(target=client, args=(c,)) for c in range(clients)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        wall = time.perf_counter() - t0
    listed = server.cli("jobs", "list", "--page_size=1000").stdout.splitlines()
    succeeded = sum(1 for line in listed if "SUCCEEDED" in line)
    after = rss_mib(server.proc.pid)
    server.stop()
    total = clients * jobs
    print("load: %d clients x %d jobs on %d^3 phantoms (%d KB each), %d workers" % (clients, jobs, n, n ** 3 // 1000,
                                                                                     os.cpu_count()))
    print("  %d/%d succeeded (%d non-zero exits), %d jobs listed SUCCEEDED" % (
        results.count(0), total, total - results.count(0), succeeded))
    print("  wall %.1f s, %.2f jobs/s; one job offline %.3f s (x%d serial / %d cores = %.1f s ideal)" % (
        wall, total / wall, one, total, os.cpu_count(), one * total / os.cpu_count()))
    print("  client-seen latency median %.2f s, max %.2f s" % (statistics.median(latencies), max(latencies)))
    print("  server RSS %.0f MiB before, peak %.0f MiB, %.0f MiB after" % (base, max(s.samples), after))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", type=pathlib.Path)
    ap.add_argument("what", nargs="?", default="all", choices=["upload", "latency", "load", "all"])
    ap.add_argument("--gib", type=int, default=1)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--clients", type=int, default=16)
    ap.add_argument("--jobs", type=int, default=4)
    ap.add_argument("--n", type=int, default=64)
    a = ap.parse_args()
    build = a.build.resolve()
    if a.what in ("upload", "all"):
        bench_upload(build, a.gib)
    if a.what in ("latency", "all"):
        bench_latency(build, a.runs)
    if a.what in ("load", "all"):
        bench_load(build, a.clients, a.jobs, a.n)


if __name__ == "__main__":
    sys.exit(main())
