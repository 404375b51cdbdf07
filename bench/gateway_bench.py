#!/usr/bin/python3
"""The HTTP gateway's cost against direct gRPC, the front-end's size and load time, and
the previews' rendering time.

- Job latency on the sample (`phantom --preset=sample`, r = 7, no cache): create, watch
  to SUCCEEDED, fetch report.json; direct with the Python client over gRPC against the
  same through sheetmesh-gateway (POST /v1/jobs, the watch as JSON lines, the artifact
  route), alternating, --runs each.
- Upload of a --upload_mb file: the Python client's Write stream (1 MiB pieces) against
  PUT chunks of 64 MiB through the gateway, each to a fresh server data folder on the same
  disk; the SHA-256 is computed before and not timed.
- The front-end: bundle sizes (web/dist), and the time from navigation to the page's
  first control in headless Chromium (median of 5).
- Previews: the seconds report.json gives for each preview of `surface --r=7` on the
  paper-scale phantom (--paper; built here once, 1 GB), against the run's read stage.

Usage: /usr/bin/python3 bench/gateway_bench.py [BUILD_DIR] [--runs 5] [--upload_mb 1024] [--paper]
"""
import argparse
import hashlib
import http.client
import json
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import uuid

ROOT = pathlib.Path(__file__).resolve().parent.parent


def wait_port(path, proc):
    deadline = time.time() + 60
    while not (path.exists() and path.read_text().endswith("\n")):
        if time.time() > deadline or proc.poll() is not None:
            raise RuntimeError("did not start")
        time.sleep(0.02)
    return int(path.read_text())


class Stack:
    """A server (one worker) and a gateway in front of it, in `tmp`."""

    def __init__(self, build, tmp, root):
        self.tmp = tmp
        tmp.mkdir(parents=True, exist_ok=True)
        self.server = subprocess.Popen(
            [str(build / "server/sheetmesh-server"), "--address=127.0.0.1:0", "--data_dir=%s" % (tmp / "data"),
             "--port_file=%s" % (tmp / "port"), "--allowed_root=%s" % root, "--workers=1"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.port = wait_port(tmp / "port", self.server)
        self.gateway = subprocess.Popen(
            [str(build / "gateway/sheetmesh-gateway"), "--listen=127.0.0.1:0", "--server=127.0.0.1:%d" % self.port,
             "--port_file=%s" % (tmp / "gport")], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.gport = wait_port(tmp / "gport", self.gateway)

    def http(self, method, path, body=None, headers=None):
        conn = http.client.HTTPConnection("127.0.0.1", self.gport, timeout=600)
        conn.request(method, path, body=body, headers=headers or {})
        resp = conn.getresponse()
        data = resp.read()
        conn.close()
        if resp.status >= 300:
            raise RuntimeError("%s %s: %d %s" % (method, path, resp.status, data[:300]))
        return data

    def close(self):
        for p in (self.gateway, self.server):
            p.terminate()
            p.wait(timeout=60)


def job_latency(stack, client, jobs_pb2, sample, runs):
    direct, gateway = [], []
    for i in range(runs):
        t = time.perf_counter()
        job = client.create_job(volume_path=str(sample), parameters={"r": 7, "labels": [255]}, no_cache=True)
        job = client.watch(job.name)
        assert job.state == jobs_pb2.SUCCEEDED, job
        rep = next(a for a in job.artifacts if a.name == "report.json")
        client.download(rep.digest, str(stack.tmp / "report_direct.json"))
        direct.append(time.perf_counter() - t)

        t = time.perf_counter()
        body = json.dumps({"request_id": uuid.uuid4().hex, "input": {"volume_path": str(sample)},
                           "parameters": {"r": 7, "labels": [255]}, "no_cache": True})
        job = json.loads(stack.http("POST", "/v1/jobs", body, {"Content-Type": "application/json"}))
        lines = stack.http("GET", "/v1/%s:watch" % job["name"]).decode().splitlines()
        last = json.loads(lines[-1])["result"]["job"]
        assert last["state"] == "SUCCEEDED", last
        stack.http("GET", "/v1/%s/artifacts/report.json" % job["name"])
        gateway.append(time.perf_counter() - t)
    return statistics.median(direct), statistics.median(gateway)


def upload(build, tmp, root, size_mb):
    from sheetmesh_client import SheetmeshClient
    path = tmp / "upload.bin"
    block = os.urandom(1 << 20)
    with open(path, "wb") as f:
        for i in range(size_mb):
            f.write(hashlib.sha256(block + i.to_bytes(4, "little")).digest() * 32768)
    data_hash = hashlib.sha256(path.read_bytes()).hexdigest()
    size = path.stat().st_size
    out = {}
    stack = Stack(build, tmp / "up_direct", root)
    try:
        client = SheetmeshClient("127.0.0.1:%d" % stack.port)
        t = time.perf_counter()
        client.upload(str(path))
        out["direct"] = time.perf_counter() - t
        client.close()
    finally:
        stack.close()
        shutil.rmtree(tmp / "up_direct", ignore_errors=True)
    stack = Stack(build, tmp / "up_gateway", root)
    try:
        base = "/v1/uploads/%s/blobs/%s/%d" % (uuid.uuid4().hex, data_hash, size)
        chunk = 64 << 20
        t = time.perf_counter()
        with open(path, "rb") as f:
            offset = 0
            while offset < size:
                piece = f.read(chunk)
                last = offset + len(piece) == size
                r = json.loads(stack.http("PUT", "%s?offset=%d%s" % (base, offset, "&finish=true" if last else ""),
                                          piece, {"Content-Type": "application/octet-stream"}))
                offset = int(r["committed_size"])
        out["gateway"] = time.perf_counter() - t
        assert r["complete"], r
    finally:
        stack.close()
        shutil.rmtree(tmp / "up_gateway", ignore_errors=True)
    path.unlink()
    return size, out


def front_end(stack):
    dist = ROOT / "web/dist"
    sizes = {str(p.relative_to(dist)): p.stat().st_size for p in sorted(dist.rglob("*")) if p.is_file()}
    script = r"""
import { chromium } from "playwright-core";
const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", headless: true, args: ["--no-sandbox"] });
const times = [];
for (let i = 0; i < 5; ++i) {
  const page = await (await browser.newContext()).newPage();
  const t = performance.now();
  await page.goto(process.argv[2]);
  await page.waitForSelector("#drop");
  times.push(performance.now() - t);
  await page.close();
}
await browser.close();
times.sort((a, b) => a - b);
console.log(JSON.stringify({ median_ms: times[2], times }));
"""
    js = ROOT / "web/tests/.load_time.mjs"
    js.write_text(script)
    try:
        out = subprocess.run(["node", str(js), "http://127.0.0.1:%d/" % stack.gport], check=True,
                             capture_output=True, text=True, cwd=ROOT / "web").stdout
    finally:
        js.unlink()
    return sizes, json.loads(out.strip().splitlines()[-1])


def previews_paper(build, tmp):
    raw = ROOT / "bench/out/paper_1012x1024x931_u8.raw"
    if not raw.exists():
        raw.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run([str(build / "worker/pipeline/sheetmesh-pipeline"), "phantom", "--preset=paper", "-o", str(raw)],
                       check=True, stdout=subprocess.DEVNULL)
    out = tmp / "paper"
    subprocess.run([str(build / "worker/pipeline/sheetmesh-pipeline"), "surface", str(raw), "--r=7",
                    "--output_formats=ply", "--similarity_hausdorff=false", "--similarity_grid_rates=", "-o", str(out)],
                   check=True, stdout=subprocess.DEVNULL)
    rep = json.load(open(out / "report.json"))
    return {p["file"]: (p["seconds"], p["width"], p["height"]) for p in rep["previews"]}, rep["seconds"]["read"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=str(ROOT / "build"))
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--upload_mb", type=int, default=1024)
    ap.add_argument("--paper", action="store_true")
    a = ap.parse_args()
    build = pathlib.Path(a.build).resolve()
    sys.path.insert(0, str(ROOT / "client/python"))
    sys.path.insert(0, str(build / "python"))
    from sheetmesh_client import SheetmeshClient
    from sheetmesh.v1 import jobs_pb2
    (ROOT / "bench/out").mkdir(exist_ok=True)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_gwbench_", dir=str(ROOT / "bench/out")))
    root = tmp / "root"
    root.mkdir()
    sample = root / "rock_128x112x96_u8.raw"
    subprocess.run([str(build / "worker/pipeline/sheetmesh-pipeline"), "phantom", "--preset=sample", "-o", str(sample)],
                   check=True, stdout=subprocess.DEVNULL)
    try:
        stack = Stack(build, tmp / "stack", root)
        try:
            client = SheetmeshClient("127.0.0.1:%d" % stack.port)
            d, g = job_latency(stack, client, jobs_pb2, sample, a.runs)
            client.close()
            print("job latency on the sample (median of %d): direct gRPC %.3f s, through the gateway %.3f s (%+.3f s)"
                  % (a.runs, d, g, g - d))
            sizes, load = front_end(stack)
            total = sum(sizes.values())
            print("front-end: %s; %.0f KB in all; loads in %.0f ms (median of 5: %s)"
                  % (", ".join("%s %.1f KB" % (k, v / 1024) for k, v in sizes.items()), total / 1024,
                     load["median_ms"], ", ".join("%.0f" % t for t in load["times"])))
        finally:
            stack.close()
        if a.upload_mb > 0:
            size, up = upload(build, tmp, root, a.upload_mb)
            print("upload of %d MiB: direct gRPC %.2f s (%.0f MB/s), through the gateway %.2f s (%.0f MB/s)"
                  % (size >> 20, up["direct"], size / up["direct"] / 1e6, up["gateway"], size / up["gateway"] / 1e6))
        if a.paper:
            prev, read = previews_paper(build, tmp)
            print("previews on the paper-scale phantom (read stage %.2f s): %s" % (read, ", ".join(
                "%s %.3f s (%dx%d)" % (k, s, w, h) for k, (s, w, h) in prev.items())))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
