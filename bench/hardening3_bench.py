#!/usr/bin/python3
"""Hardening, third round (issue 63): each of the audit's twelve failures run again, on this
build and (with --old) on the build before the round, in the same run.

    /usr/bin/python3 bench/hardening3_bench.py BUILD [--old OLD_BUILD] [--items 1,2,...]

Per item and build: how it ended (exit code, signal, or the job's state and error code), the
seconds and the peak resident memory of the command (`sheetmesh-pipeline` under GNU time,
an address-space limit of --as_gib (8) and a timeout of --timeout (150 s)), and a word on
the outcome. Items 5 and 12 start the server (and, for 12, the gateway) of each build;
item 11 runs deploy/slurm/submit_bricks.sh of each tree (OLD_BUILD's parent folder) with a
fake sbatch. Files live under bench/out/hardening3.
"""
import argparse
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent
OUT = ROOT / "out" / "hardening3"
sys.path.insert(0, str(ROOT.parent / "client" / "python"))


def pipeline(build):
    return str(build / "worker" / "pipeline" / "sheetmesh-pipeline")


def measure(cmd, timeout, as_gib, env=None):
    """(exit or -signal or 'timeout', seconds, peak MiB, last stderr line)."""
    t0 = time.perf_counter()
    r = subprocess.run(["prlimit", "--as=%d" % (as_gib << 30), "timeout", "-s", "KILL", str(timeout),
                        "/usr/bin/time", "-f", "peak_kib=%M", *cmd],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                       env=dict(os.environ, SHEETMESH_NO_HUGE_PAGES="1", **(env or {})))
    secs = time.perf_counter() - t0
    lines = r.stderr.strip().splitlines()
    kib = next((int(l.split("=")[1]) for l in lines if l.startswith("peak_kib=")), 0)
    died = next((l for l in lines if l.startswith("Command terminated by signal")), None)
    code = r.returncode
    if code == 137 and secs >= timeout - 1:
        code = "timeout"
    elif died:
        code = -int(died.split()[-1])
    last = next((l for l in reversed(lines) if not l.startswith(("peak_kib=", "Command "))), "")
    return code, secs, kib / 1024, last


def sample(build, folder, dims=None):
    name = "sample_%s_u8.raw" % ("128x112x96" if dims is None else dims)
    vol = folder / name
    if not vol.exists():
        cmd = [pipeline(build), "phantom", "--preset=sample", "-o", str(vol)]
        if dims:
            cmd.append("--dims=" + dims)
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return vol


def changed_vdb(build, folder, at, value):
    whole = folder / "full.vdb"
    if not whole.exists():
        subprocess.run([pipeline(build), "convert", str(sample(build, folder)), "-o", str(whole),
                        "--out_format=vdb"], check=True, stdout=subprocess.DEVNULL)
    data = bytearray(whole.read_bytes())
    data[at] = value
    path = folder / ("changed_%d_%d.vdb" % (at, value))
    path.write_bytes(bytes(data))
    return path


def offline_items(folder, build, old):
    """(item, label, command) of the offline items, for `build` (`old`: the build before
    this round, which reads every file in its own process and has no --isolate_readers)."""
    P = pipeline(build)
    vol = sample(build, folder)
    small = sample(build, folder, "80x80x80")
    config = folder / "r_1e999.json"
    config.write_text('{"r": 1e999}\n')
    scales = ",".join(["1"] * 10000)
    items = []
    for at, value in ((2167, 79), (78941, 128), (1357, 127)):
        path = changed_vdb(build, folder, at, value)
        if not old:
            items.append((1 if at != 1357 else 2, "vdb byte %d = %d, in process" % (at, value),
                          [P, "info", str(path), "--isolate_readers=false"]))
        items.append((1 if at != 1357 else 2, "vdb byte %d = %d" % (at, value),
                      [P, "info", str(path)]))
    items.append((3, "config r = 1e999", [P, "run", str(vol), "-o", str(folder / "x"),
                                          "--config=%s" % config]))
    items.append((4, "surface.bricks = 1", [P, "run", str(vol), "-o", str(folder / "x"),
                                            "--surface_bricks=1"]))
    items.append((4, "surface.bricks = 8, halo 0", [P, "run", str(vol), "-o", str(folder / "x"),
                                                     "--surface_bricks=8", "--surface_bricks_halo=0"]))
    items.append((6, "grey.scales of 10,000", [P, "run", str(grey_scan(vol)), "-o", str(folder / "x"),
                                               "--grey", "--grey_scales=" + scales]))
    items.append((7, "max_tetrahedra 1e12, lattice 0.25, grading 0.1, limit 20 s",
                  [P, "run", str(vol), "-o", str(folder / "t7"), "--volume_mesh",
                   "--max_tetrahedra=1e12", "--plc_lattice=0.25", "--plc_grading=0.1",
                   "--tet_time_limit_seconds=20", "--similarity_hausdorff=false"]))
    items.append((8, "permeability.matrix = 5e-324", [P, "run", str(small), "-o", str(folder / "k8"),
                                                      "--flow", "--unit=um", "--spacing=5,5,5",
                                                      "--permeability_matrix=5e-324"]))
    items.append((9, "spacing 1e-12 m with flow", [P, "run", str(small), "-o", str(folder / "k9"),
                                                   "--flow", "--unit=m", "--spacing=1e-12,1e-12,1e-12"]))
    items.append((10, "merge of a 1048576^3 plan in bricks of 1", [P, "merge", str(edited_plan(build, folder, small)),
                                                                   "-o", str(folder / "m10")]))
    return items


def grey_scan(vol):
    """The sample as a grey scan: dark sheets (50) in bright rock (200), blurred, noisy."""
    import numpy as np
    from scipy.ndimage import gaussian_filter
    out = vol.with_name(vol.name.replace("_u8.raw", "_f32.raw").replace("sample_", "grey_"))
    if not out.exists():
        a = np.fromfile(vol, np.uint8).reshape(96, 112, 128).astype(np.float32)
        g = gaussian_filter(np.where(a > 0, 50.0, 200.0), 1.0)
        g += np.random.default_rng(3).normal(0, 8, g.shape)
        g.astype(np.float32).tofile(out)
    return out


def edited_plan(build, folder, vol):
    plan = folder / ("plan_%s" % build.name)
    subprocess.run(["rm", "-rf", str(plan)])
    subprocess.run([pipeline(build), "plan", str(vol), "-o", str(plan), "--brick_size=40"], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for i in range(8):
        subprocess.run([pipeline(build), "brick", str(plan), "--index=%d" % i], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    j = json.loads((plan / "plan.json").read_text())
    j["dims"] = [1048576] * 3
    j["brick_size"] = [1, 1, 1]
    (plan / "plan.json").write_text(json.dumps(j))
    return plan


def wait_port(path, proc):
    deadline = time.time() + 60
    while not (path.exists() and path.read_text().endswith("\n")):
        if time.time() > deadline or proc.poll() is not None:
            raise RuntimeError("did not start")
        time.sleep(0.02)
    return int(path.read_text())


def server_for(build, folder, flags=()):
    subprocess.run(["rm", "-rf", str(folder)])
    folder.mkdir(parents=True)
    proc = subprocess.Popen([str(build / "server/sheetmesh-server"), "--address=127.0.0.1:0",
                             "--data_dir=%s" % (folder / "data"), "--port_file=%s" % (folder / "port"),
                             "--workers=1", "--allowed_root=%s" % folder, *flags],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return proc, wait_port(folder / "port", proc)


def item5(build, folder, old):
    """A job with bricks 4x4x4 on the sample, then one of 16x16x16 on a 256x224x192 phantom
    (2,688 bricks, the server's limits raised so that the new build splits it): the tasks
    made and the seconds its cancel takes."""
    import grpc
    from sheetmesh_client import SheetmeshClient as Client, SheetmeshError
    rows = []
    proc, port = server_for(build, folder, ["--max_queued_jobs=100000"] if old else
                            ["--max_brick_tasks=100000", "--max_queued_jobs=100000"])
    try:
        client = Client("127.0.0.1:%d" % port)
        vol = sample(build, folder)
        big = sample(build, folder, "256x224x192")
        for bricks, path in (("4x4x4", vol), ("16x16x16", big)):
            t0 = time.perf_counter()
            try:
                job = client.create_job(volume_path=str(path), bricks=bricks, no_cache=True)
            except (SheetmeshError, grpc.RpcError) as e:
                rows.append((5, "bricks %s: refused at create" % bricks, "refused", time.perf_counter() - t0,
                             0, str(e)[:90]))
                continue
            count = 0
            while time.perf_counter() - t0 < 300:
                j = client.get_job(job.name)
                count = j.bricks.count
                if count or j.state in (4, 5, 6):
                    break
                time.sleep(0.2)
            split_s = time.perf_counter() - t0
            t1 = time.perf_counter()
            client.cancel_job(job.name)
            cancel_s = time.perf_counter() - t1
            j = client.get_job(job.name)
            rows.append((5, "bricks %s: %d tasks; cancel" % (bricks, count), j.state, cancel_s, 0,
                         "split after %.1f s; %s" % (split_s, j.error.message[:70])))
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(30)
    return rows


def item11(tree, folder):
    """deploy/slurm/submit_bricks.sh of `tree` with an output folder named out'$(touch PWNED)'x."""
    test = ROOT.parent / "tests/deploy/slurm_quoting_test.sh"
    t0 = time.perf_counter()
    r = subprocess.run(["bash", str(test), str(tree)], capture_output=True, text=True)
    line = (r.stdout + r.stderr).strip().splitlines()[-1:] or [""]
    return [(11, "submit_bricks.sh with out'$(touch PWNED)'x", r.returncode, time.perf_counter() - t0, 0,
             line[0][:90])]


def item12(build, folder):
    """A POST whose Origin and Host are both evil.example:PORT, through the gateway."""
    import http.client
    gw_bin = build / "gateway/sheetmesh-gateway"
    if not gw_bin.exists():
        return [(12, "gateway, rebinding origin", "no gateway built", 0, 0, "")]
    proc, port = server_for(build, folder)
    gw = subprocess.Popen([str(gw_bin), "--listen=127.0.0.1:0", "--server=127.0.0.1:%d" % port,
                           "--port_file=%s" % (folder / "gport")], stdout=subprocess.DEVNULL,
                          stderr=subprocess.DEVNULL)
    try:
        gport = wait_port(folder / "gport", gw)
        evil = "evil.example:%d" % gport
        conn = http.client.HTTPConnection("127.0.0.1", gport, timeout=30)
        t0 = time.perf_counter()
        conn.request("POST", "/v1/jobs", body=json.dumps({"request_id": "rebind"}),
                     headers={"Origin": "http://" + evil, "Host": evil,
                              "Content-Type": "application/json"})
        resp = conn.getresponse()
        body = resp.read().decode(errors="replace")
        return [(12, "gateway, Origin = Host = evil.example", resp.status, time.perf_counter() - t0, 0,
                 body[:90])]
    finally:
        gw.send_signal(signal.SIGTERM)
        proc.send_signal(signal.SIGTERM)
        gw.wait(30)
        proc.wait(30)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("build", type=pathlib.Path)
    ap.add_argument("--old", type=pathlib.Path)
    ap.add_argument("--items", default="1,2,3,4,5,6,7,8,9,10,11,12")
    ap.add_argument("--timeout", type=int, default=150)
    ap.add_argument("--as_gib", type=int, default=8)
    args = ap.parse_args()
    wanted = {int(i) for i in args.items.split(",")}
    builds = [("new", args.build.resolve())]
    if args.old:
        builds.insert(0, ("old", args.old.resolve()))
    print("| item | case | build | ended | seconds | peak MiB | message |")
    print("|---|---|---|---|---|---|---|")
    # The client's stubs are this build's (the wire is the same for both servers).
    os.environ.setdefault("SHEETMESH_PYTHON_STUBS", str(args.build.resolve() / "python"))
    for name, build in builds:
        folder = OUT / name
        folder.mkdir(parents=True, exist_ok=True)

        def show(rows):
            for item, label, code, secs, mib, last in rows:
                last = last.replace(str(folder) + "/", "").replace("sheetmesh-pipeline ", "")
                print("| %d | %s | %s | %s | %.2f | %.0f | %s |" % (
                    item, label, name, code, secs, mib, last[:110].replace("|", "/")), flush=True)

        for item, label, cmd in offline_items(folder, build, name == "old"):
            if item in wanted:
                code, secs, mib, last = measure(cmd, args.timeout, args.as_gib)
                show([(item, label, code, secs, mib, last)])
        for item, run in ((5, lambda: item5(build, folder / "server", name == "old")),
                          (11, lambda: item11(build.parent if name == "old" else ROOT.parent, folder)),
                          (12, lambda: item12(build, folder / "gateway"))):
            if item in wanted:
                try:
                    show(run())
                except Exception as e:  # a bench row, not the end of the bench
                    show([(item, "(failed to measure)", "error", 0, 0, repr(e)[:100])])


if __name__ == "__main__":
    main()
