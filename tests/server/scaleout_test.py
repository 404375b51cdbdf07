#!/usr/bin/python3
"""The scale-out shape under faults, with real processes on loopback: two servers
(--local_workers=false) over one PostgreSQL and one blob folder, three sheetmesh-workers;
100 jobs from 8 client threads across both servers; one worker SIGKILLed and one server
SIGKILLed (and started again) mid-run. Every job ends SUCCEEDED, none is lost, none runs
to completion twice, every artifact's digest is right. And one job run as bricks (36 brick
tasks on the same queue), its only worker SIGKILLed while it runs a brick: the brick runs
again on the workers started after, once, and the merge gives the one-process surface.

    /usr/bin/python3 tests/server/scaleout_test.py SERVER_BIN WORKER_BIN PIPELINE_BIN
(SHEETMESH_PYTHON_STUBS; SHEETMESH_TEST_POSTGRES_FILE from tools/pg_cluster.sh; exits 77
without a cluster.)
"""
import concurrent.futures
import hashlib
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import unittest

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent / "client" / "python"))
sys.path.insert(0, str(HERE.parent / "testing"))
from ports import wait_port_file  # noqa: E402

SERVER_BIN = WORKER_BIN = PIPELINE_BIN = CONNINFO = None


class ScaleOutTest(unittest.TestCase):
    def setUp(self):
        from sheetmesh.v1 import jobs_pb2
        self.pb = jobs_pb2
        self.tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_scaleout_"))
        self.db = "scaleout_%d" % os.getpid()
        subprocess.run(["psql", CONNINFO, "-q", "-c", "CREATE DATABASE %s" % self.db], check=True)
        self.conninfo = "%s dbname=%s" % (CONNINFO, self.db)
        (self.tmp / "wtoken").write_text("scaleout-worker\n")
        self.root = self.tmp / "root"
        self.root.mkdir()
        self.sample = self.root / "rock_128x112x96_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--preset=sample", "-o", str(self.sample)], check=True,
                       stdout=subprocess.DEVNULL)
        self.procs = []

    def tearDown(self):
        for p in self.procs:
            if p.poll() is None:
                p.terminate()
                p.wait(timeout=60)
        subprocess.run(["psql", CONNINFO, "-q", "-c", "DROP DATABASE %s WITH (FORCE)" % self.db])
        shutil.rmtree(self.tmp, ignore_errors=True)

    def server(self, name):
        port = self.tmp / ("%s.port" % name)
        port.unlink(missing_ok=True)
        log = open(self.tmp / ("%s.log" % name), "a")
        p = subprocess.Popen([SERVER_BIN, "--address=127.0.0.1:0", "--data_dir=%s" % (self.tmp / "shared"),
                              "--scratch_dir=%s" % (self.tmp / ("scratch-" + name)), "--postgres=%s" % self.conninfo,
                              "--port_file=%s" % port, "--allowed_root=%s" % self.root, "--local_workers=false",
                              "--worker_token_file=%s" % (self.tmp / "wtoken"), "--lease_seconds=3",
                              "--heartbeat_seconds=1"], stdout=subprocess.DEVNULL, stderr=log)
        log.close()  # the server has its own copy
        self.procs.append(p)
        # A server that exits before serving says why in its log (under load one of the
        # hundred-job test's servers once did, unexplained).
        return p, "127.0.0.1:%d" % wait_port_file(port, p, "server " + name,
                                                   log=self.tmp / ("%s.log" % name))

    def worker(self, name, address):
        p = subprocess.Popen([WORKER_BIN, "--server=%s" % address, "--token_file=%s" % (self.tmp / "wtoken"),
                              "--scratch_dir=%s" % (self.tmp / ("w-" + name)), "--allowed_root=%s" % self.root,
                              "--workers=1", "--renew_seconds=1", "--name=%s" % name],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.procs.append(p)
        return p

    def test_a_hundred_jobs_through_two_servers_and_three_workers_with_a_worker_and_a_server_killed(self):
        from sheetmesh_client import SheetmeshClient
        a, a_addr = self.server("a")
        b, b_addr = self.server("b")
        # Two workers on a, one on b: killing a takes its two workers' connections with it
        # too, so they must find their server again (they retry) — or their jobs go elsewhere.
        w1 = self.worker("w1", a_addr)
        self.worker("w2", b_addr)
        self.worker("w3", b_addr)
        names, lock = [], threading.Lock()

        def submit(k):
            client = SheetmeshClient(b_addr if k % 2 else a_addr)
            try:
                for i in range(k, 100, 8):
                    j = client.create_job(volume_path=str(self.sample),
                                          parameters={"r": 6 + (i % 5) * 0.5, "labels": [255]},
                                          request_id="scaleout-%d" % i, no_cache=True)
                    with lock:
                        names.append(j.name)
            finally:
                client.close()

        with concurrent.futures.ThreadPoolExecutor(8) as pool:
            list(pool.map(submit, range(8)))
        self.assertEqual(len(set(names)), 100)
        watcher = SheetmeshClient(b_addr)
        # Mid-run: a worker dies, then server a dies and comes back on a new port.
        deadline = time.time() + 120
        while sum(1 for n in names if watcher.get_job(n).state == self.pb.SUCCEEDED) < 15:
            self.assertLess(time.time(), deadline, "jobs do not progress")
            time.sleep(0.2)
        w1.send_signal(signal.SIGKILL)
        a.send_signal(signal.SIGKILL)
        a.wait()
        a2, a2_addr = self.server("a2")
        self.worker("w4", a2_addr)
        done = {}
        deadline = time.time() + 600
        while len(done) < 100:
            self.assertLess(time.time(), deadline, "%d of 100 jobs ended" % len(done))
            for n in names:
                if n not in done:
                    j = watcher.get_job(n)
                    if j.state in (self.pb.SUCCEEDED, self.pb.FAILED, self.pb.CANCELLED):
                        done[n] = j
            time.sleep(0.2)
        failed = [(n, j.error.message) for n, j in done.items() if j.state != self.pb.SUCCEEDED]
        self.assertEqual(failed, [])
        rerun = sum(1 for j in done.values() if j.attempts > 1)
        # Each job ends once: its single stored record says SUCCEEDED with one set of artifacts.
        for j in done.values():
            names_ = [a.name for a in j.artifacts]
            self.assertEqual(len(names_), len(set(names_)), "%s has duplicated artifacts" % j.name)
        checked = 0
        for j in done.values():
            for art in j.artifacts:
                out = self.tmp / "dl.bin"
                watcher.download(art.digest, str(out))
                self.assertEqual(hashlib.sha256(out.read_bytes()).hexdigest(), art.digest.hash)
                checked += 1
        watcher.close()
        print("100 jobs SUCCEEDED, %d run again after the kills, %d artifacts digest-checked" % (rerun, checked))

    def test_a_bricked_job_over_postgres_survives_a_killed_worker_and_gives_the_one_process_surface(self):
        from sheetmesh_client import SheetmeshClient
        _, a_addr = self.server("a")
        _, b_addr = self.server("b")
        client = SheetmeshClient(a_addr)
        watcher = SheetmeshClient(b_addr)
        params = {"r": 5, "labels": [255]}
        one = client.create_job(volume_path=str(self.sample), parameters=params, request_id="one", no_cache=True)
        bricked = client.create_job(volume_path=str(self.sample), parameters=params, request_id="bricked",
                                    no_cache=True, bricks="48x40x24")
        # One worker first: the brick it runs when it is killed is surely its.
        w1 = self.worker("w1", a_addr)
        deadline = time.time() + 120
        while True:
            self.assertLess(time.time(), deadline, "no brick started")
            j = watcher.get_job(bricked.name)
            running = [t for t in j.bricks.tasks if watcher.get_job(t).state == self.pb.RUNNING]
            if running:
                break
            time.sleep(0.05)
        w1.send_signal(signal.SIGKILL)
        w1.wait()
        # The bricks RUNNING now are the dead worker's: no other worker has started yet. The one seen
        # above may have ended between the look and the kill, and the worker taken the next.
        held = [t for t in watcher.get_job(bricked.name).bricks.tasks
                if watcher.get_job(t).state == self.pb.RUNNING]
        self.assertLessEqual(len(held), 1, held)
        interrupted = bool(held)
        killed = held[0] if held else running[0]
        self.worker("w2", a_addr)
        self.worker("w3", b_addr)
        messages = []
        done = watcher.watch(bricked.name, on_update=lambda job, _: messages.append(job.progress.message)
                             if job.progress.stage == "bricks" else None)
        first = watcher.watch(one.name)
        self.assertEqual(done.state, self.pb.SUCCEEDED, done.error.message)
        self.assertEqual(first.state, self.pb.SUCCEEDED, first.error.message)
        n = done.bricks.count
        self.assertEqual(n, 3 * 3 * 4)
        tasks = [watcher.get_job(t) for t in done.bricks.tasks]
        self.assertTrue(all(t.state == self.pb.SUCCEEDED for t in tasks))
        self.assertEqual(sorted(t.bricks.index for t in tasks), list(range(n)))
        # The killed worker's brick ran again, once; no other ran twice.
        self.assertEqual({t.name: t.attempts for t in tasks if t.attempts > 1},
                         {killed: 2} if interrupted else {})
        self.assertTrue(any("bricks done" in m for m in messages), messages)
        mine = {a.name: a.digest.hash for a in done.artifacts}
        theirs = {a.name: a.digest.hash for a in first.artifacts}
        self.assertEqual(mine["surface.ply"], theirs["surface.ply"])
        self.assertIn("bricks.json", mine)
        # Bricks are not listed as the tenant's jobs.
        self.assertEqual(sorted(j.name for j in client.list_jobs()), sorted([one.name, bricked.name]))
        client.close()
        watcher.close()
        print("%d bricks over two servers; the killed worker's brick %s %s; the same surface" %
              (n, killed, "ran again" if interrupted else "had ended before the kill"))


if __name__ == "__main__":
    SERVER_BIN, WORKER_BIN, PIPELINE_BIN = sys.argv[1:4]
    del sys.argv[1:4]
    f = os.environ.get("SHEETMESH_TEST_POSTGRES_FILE", "")
    CONNINFO = os.environ.get("SHEETMESH_TEST_POSTGRES") or (open(f).read().strip() if f and os.path.exists(f) else "")
    if not CONNINFO:
        print("SKIP: no PostgreSQL test cluster (SHEETMESH_TEST_POSTGRES_FILE; tools/pg_cluster.sh starts one)")
        sys.exit(77)
    sys.path.insert(0, os.environ.get("SHEETMESH_PYTHON_STUBS", ""))
    unittest.main(verbosity=2)
