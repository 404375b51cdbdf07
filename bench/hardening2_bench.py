#!/usr/bin/python3
"""Hardening, second round (issue 40): the audit's figures measured again.

    /usr/bin/python3 bench/hardening2_bench.py BUILD bombs [--old OLD_BUILD]
    /usr/bin/python3 bench/hardening2_bench.py BUILD runaway [--old OLD_BUILD]
    /usr/bin/python3 bench/hardening2_bench.py BUILD gateway [--slow 100]
    /usr/bin/python3 bench/hardening2_bench.py BUILD soak [--jobs 36] [--soak_dims 200] [--old OLD_BUILD]

- bombs: small files that claimed gigabytes or minutes (an HDF5 dataset in one 1 GiB gzip
  chunk, 2,000 nested HDF5 groups, a .npy with a 40 KB shape, a 600-byte JPEG and a PNG
  claiming 65500 x 65500, a .vdb cut to 200 bytes): exit, seconds and peak RSS of
  `sheetmesh-pipeline info FILE` under a 16 GiB address-space limit.
- runaway: parameters in range that ran away on the sample phantom (detect.t = 100,
  detect.R = 1000, tet.min_dihedral = 69.99, spacing 1e-6): exit, seconds, peak RSS of
  `run` (a 300 s limit each).
- gateway: sheetmesh-gateway's RSS while a client announces a 256 MiB POST body, and while
  --slow clients trickle one byte every 5 s without a token: how many it still holds.
- soak: --jobs jobs on the sample, the server SIGKILLed every 1-4 s and started again
  until all end (--max_attempts 3, the default): how many FAILED, lost_to_restarts.

OLD_BUILD is a build of the version before, measured in the same run (a folder with
worker/pipeline/sheetmesh-pipeline). Files and servers live under bench/out/hardening2.
"""
import argparse
import http.client
import os
import pathlib
import random
import signal
import socket
import struct
import subprocess
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent
OUT = ROOT / "out" / "hardening2"


def pipeline(build):
    return str(build / "worker" / "pipeline" / "sheetmesh-pipeline")


def measure(cmd, limit_s=300, as_limit=16 << 30):
    """(exit, seconds, peak MiB) of cmd under GNU time, an address-space limit and a timeout."""
    t0 = time.perf_counter()
    r = subprocess.run(["prlimit", "--as=%d" % as_limit, "timeout", str(limit_s), "/usr/bin/time", "-f",
                        "%M", *cmd], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    secs = time.perf_counter() - t0
    lines = [l for l in r.stderr.strip().splitlines() if l.strip().isdigit()]
    kib = int(lines[-1]) if lines else 0
    return r.returncode, secs, kib / 1024


def sample(build, folder):
    vol = folder / "sample_128x112x96_u8.raw"
    if not vol.exists():
        subprocess.run([pipeline(build), "phantom", "--preset=sample", "-o", str(vol)], check=True,
                       stdout=subprocess.DEVNULL)
    return vol


def make_bombs(build, folder):
    import h5py
    from PIL import Image
    import io
    files = []
    p = folder / "chunk.h5"
    with h5py.File(p, "w") as f:  # 48^3 in one chunk of 1024^3 (1 GiB decoded)
        d = f.create_dataset("data", shape=(48, 48, 48), maxshape=(None, None, None), dtype="u1",
                             chunks=(1024, 1024, 1024), compression="gzip")
        d[:, :, 24] = 255
    files.append(("HDF5 48^3 in one 1 GiB gzip chunk (%d KB)" % (p.stat().st_size // 1024), p))
    p = folder / "nested.h5"
    with h5py.File(p, "w") as f:
        g = f
        for _ in range(2000):
            g = g.create_group("g")
        g.create_dataset("data", data=np.ones((4, 4, 4), np.uint8))
    files.append(("HDF5 with 2,000 nested groups (%d KB)" % (p.stat().st_size // 1024), p))
    p = folder / "long.npy"
    header = "{'descr': '|u1', 'fortran_order': False, 'shape': (" + "1," * 20000 + "), }"
    header += " " * ((64 - (len(header) + 13) % 64) % 64) + "\n"
    p.write_bytes(b"\x93NUMPY\x02\x00" + struct.pack("<I", len(header)) + header.encode() + b"\x01")
    files.append((".npy with a 40 KB shape tuple", p))
    for kind in ("jpeg", "png"):
        d = folder / ("claim_" + kind)
        d.mkdir(exist_ok=True)
        b = io.BytesIO()
        Image.new("L", (16, 16), 200).save(b, "JPEG" if kind == "jpeg" else "PNG")
        data = bytearray(b.getvalue())
        if kind == "jpeg":
            at = data.find(b"\xff\xc0")
            data[at + 5:at + 9] = struct.pack(">HH", 65500, 65500)
        else:
            import zlib
            data[16:24] = struct.pack(">II", 65500, 65500)
            data[29:33] = struct.pack(">I", zlib.crc32(bytes(data[12:29])))
        (d / ("slice_0000." + ("jpg" if kind == "jpeg" else "png"))).write_bytes(bytes(data))
        files.append(("%s slice of %d B claiming 65500 x 65500" % (kind.upper(), len(data)), d))
    vol = sample(build, folder)
    whole = folder / "whole.vdb"
    subprocess.run([pipeline(build), "convert", str(vol), "-o", str(whole), "--out_format=vdb"], check=True,
                   stdout=subprocess.DEVNULL)
    p = folder / "cut200.vdb"
    p.write_bytes(whole.read_bytes()[:200])
    files.append((".vdb cut to its first 200 bytes", p))
    return files


def bench_bombs(build, old):
    folder = OUT / "bombs"
    folder.mkdir(parents=True, exist_ok=True)
    files = make_bombs(build, folder)
    builds = [("this build", build)] + ([("before", old)] if old else [])
    print("`sheetmesh-pipeline info FILE` under a 16 GiB address-space limit: exit, seconds, peak RSS")
    for label, path in files:
        line = "  %-48s" % label
        for name, b in builds:
            code, secs, mib = measure([pipeline(b), "info", str(path)])
            line += "  %s: exit %3d, %6.2f s, %6.0f MiB" % (name, code, secs, mib)
        print(line, flush=True)


def bench_runaway(build, old):
    folder = OUT / "runaway"
    folder.mkdir(parents=True, exist_ok=True)
    vol = sample(build, folder)
    cases = [("--extract --detect_t=100", ["--extract", "--detect_t=100"]),
             ("--extract --detect_R=1000", ["--extract", "--detect_R=1000"]),
             ("--volume_mesh --tet_min_dihedral=69.99", ["--volume_mesh", "--tet_min_dihedral=69.99"]),
             ("--spacing=1e-6,1e-6,1e-6 --unit=m", ["--spacing=1e-6,1e-6,1e-6", "--unit=m"]),
             ("defaults, for scale", [])]
    builds = [("this build", build)] + ([("before", old)] if old else [])
    print("`sheetmesh-pipeline run SAMPLE` (300 s limit): exit, seconds, peak RSS")
    for label, flags in cases:
        line = "  %-42s" % label
        for name, b in builds:
            code, secs, mib = measure([pipeline(b), "run", str(vol), "-o", str(folder / "out")] + flags)
            line += "  %s: exit %3d, %6.1f s, %6.0f MiB" % (name, code, secs, mib)
        print(line, flush=True)


def rss_mib(pid):
    for line in open("/proc/%d/status" % pid):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0


def wait_port(path, proc):
    deadline = time.time() + 60
    while not (path.exists() and path.read_text().endswith("\n")):
        if time.time() > deadline or proc.poll() is not None:
            raise RuntimeError("did not start")
        time.sleep(0.02)
    return int(path.read_text())


def bench_gateway(build, slow):
    folder = OUT / "gateway"
    subprocess.run(["rm", "-rf", str(folder)])
    folder.mkdir(parents=True)
    (folder / "token").write_text("bench-token-0123456789\n")
    server = subprocess.Popen([str(build / "server/sheetmesh-server"), "--address=127.0.0.1:0",
                               "--data_dir=%s" % (folder / "data"), "--port_file=%s" % (folder / "port"),
                               "--auth_token_file=%s" % (folder / "token"), "--workers=1"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    port = wait_port(folder / "port", server)
    gw = subprocess.Popen([str(build / "gateway/sheetmesh-gateway"), "--listen=127.0.0.1:0",
                           "--server=127.0.0.1:%d" % port, "--port_file=%s" % (folder / "gport")],
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    gport = wait_port(folder / "gport", gw)
    try:
        base = rss_mib(gw.pid)
        # A client announcing 256 MiB and sending it as fast as it can.
        s = socket.create_connection(("127.0.0.1", gport))
        s.sendall(b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer bench-token-0123456789\r\n"
                  b"Content-Type: application/json\r\nContent-Length: %d\r\n\r\n" % (256 << 20))
        sent, peak = 0, base
        t0 = time.time()
        s.settimeout(5)
        try:
            chunk = b" " * (1 << 20)
            while sent < (256 << 20) and time.time() - t0 < 30:
                s.sendall(chunk)
                sent += len(chunk)
                peak = max(peak, rss_mib(gw.pid))
        except OSError:
            pass
        answer = b""
        try:
            answer = s.recv(200)
        except OSError:
            pass
        s.close()
        peak = max(peak, rss_mib(gw.pid))
        status = answer.split(b"\r\n", 1)[0].decode(errors="replace")
        print("gateway RSS %.0f MiB before; a 256 MiB POST body: answered '%s' after %d MiB were sent; peak RSS %.0f MiB"
              % (base, status, sent >> 20, peak))
        # Tokenless clients trickling a body one byte every 5 s.
        conns = []
        for _ in range(slow):
            c = socket.create_connection(("127.0.0.1", gport))
            c.sendall(b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                      b"Content-Length: 1000\r\n\r\n{")
            c.setblocking(False)
            conns.append(c)
        t0 = time.time()
        open_after = {}
        while time.time() - t0 < 60:
            time.sleep(5)
            for c in conns:
                try:
                    c.send(b" ")
                except OSError:
                    pass
            alive = 0
            for c in conns:
                try:  # read what the gateway answered; a closed connection then reads b""
                    while c.recv(65536):
                        pass
                except BlockingIOError:
                    alive += 1
                except OSError:
                    pass
            open_after[round(time.time() - t0)] = alive
        print("%d tokenless clients trickling 1 byte / 5 s: connections the gateway still holds by second: %s; RSS %.0f MiB"
              % (slow, open_after, rss_mib(gw.pid)))
        for c in conns:
            c.close()
    finally:
        gw.terminate()
        server.terminate()
        gw.wait()
        server.wait()


def bench_soak(build, jobs, seed, side, server_build=None):
    rng = random.Random(seed)
    folder = OUT / "soak"
    subprocess.run(["rm", "-rf", str(folder)])
    (folder / "root").mkdir(parents=True)
    # Jobs of several seconds each (extraction on a side^3 phantom), so that kills every
    # 1-4 s land in their runs again and again.
    vol = folder / "root" / ("soak_%dx%dx%d_u8.raw" % (side, side, side))
    subprocess.run([pipeline(build), "phantom", "--dims=%dx%dx%d" % (side, side, side), "--seed=23", "--sheets=4",
                    "-o", str(vol)], check=True, stdout=subprocess.DEVNULL)
    server_bin = str((server_build or build) / "server/sheetmesh-server")
    os.environ["SHEETMESH_PYTHON_STUBS"] = str(build / "python")
    sys.path.insert(0, str(ROOT.parent / "client" / "python"))
    import sheetmesh_client  # noqa: E402
    from sheetmesh.v1 import jobs_pb2  # noqa: E402

    def start():
        port = folder / "port"
        if port.exists():
            port.unlink()
        proc = subprocess.Popen([server_bin, "--address=127.0.0.1:0",
                                 "--data_dir=%s" % (folder / "data"), "--port_file=%s" % port,
                                 "--allowed_root=%s" % (folder / "root"), "--workers=2", "--lease_seconds=3"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return proc, "127.0.0.1:%d" % wait_port(port, proc)

    proc, address = start()
    client = sheetmesh_client.SheetmeshClient(address)
    names = [client.create_job(volume_path=str(vol), request_id="soak-%d" % i, no_cache=True,
                               parameters={"extract": True, "r": 5 + (i % 6)}).name for i in range(jobs)]
    client.close()
    kills, t0 = 0, time.time()
    final = {}
    while len(final) < jobs and time.time() - t0 < 1800:
        time.sleep(rng.uniform(1, 4))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        kills += 1
        proc, address = start()
        with sheetmesh_client.SheetmeshClient(address) as c:
            for n in names:
                j = c.get_job(n)
                if j.state in (jobs_pb2.SUCCEEDED, jobs_pb2.FAILED, jobs_pb2.CANCELLED):
                    final[n] = j
    with sheetmesh_client.SheetmeshClient(address) as c:
        while len(final) < jobs:
            for n in names:
                j = c.get_job(n)
                if j.state in (jobs_pb2.SUCCEEDED, jobs_pb2.FAILED, jobs_pb2.CANCELLED):
                    final[n] = j
            time.sleep(0.5)
    proc.terminate()
    proc.wait()
    states = {}
    for j in final.values():
        states[jobs_pb2.JobState.Name(j.state)] = states.get(jobs_pb2.JobState.Name(j.state), 0) + 1
    lost = [j.lost_to_restarts for j in final.values()]
    print("soak (%s): %d jobs (extract, r 5-10, a %d^3 phantom), the server SIGKILLed every 1-4 s (%d kills, "
          "%.0f s), max_attempts 3" % (server_bin, jobs, side, kills, time.time() - t0))
    print("  ended: %s; runs lost to restarts per job: max %d, total %d; attempts max %d" % (
        states, max(lost), sum(lost), max(j.attempts for j in final.values())))
    for j in final.values():
        if j.state != jobs_pb2.SUCCEEDED:
            print("  %s %s: %s" % (j.name, jobs_pb2.JobState.Name(j.state), j.error.message))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", type=pathlib.Path)
    ap.add_argument("what", choices=["bombs", "runaway", "gateway", "soak"])
    ap.add_argument("--old", type=pathlib.Path)
    ap.add_argument("--slow", type=int, default=100)
    ap.add_argument("--jobs", type=int, default=36)
    ap.add_argument("--seed", type=int, default=40)
    ap.add_argument("--soak_dims", type=int, default=200)
    a = ap.parse_args()
    build = a.build.resolve()
    old = a.old.resolve() if a.old else None
    if a.what == "bombs":
        bench_bombs(build, old)
    elif a.what == "runaway":
        bench_runaway(build, old)
    elif a.what == "gateway":
        bench_gateway(build, a.slow)
    else:
        bench_soak(build, a.jobs, a.seed, a.soak_dims)
        if old:
            bench_soak(build, a.jobs, a.seed, a.soak_dims, server_build=old)


if __name__ == "__main__":
    main()
