#!/usr/bin/python3
"""Two sheetmesh-server replicas over one PostgreSQL and one blob folder, as real processes
on loopback: jobs created on either are run by either, seen and cancelled through the
other, and a job whose server is SIGKILLed mid-run is run again by the other.

    /usr/bin/python3 tests/server/replicas_test.py SERVER_BIN PIPELINE_BIN
(SHEETMESH_PYTHON_STUBS: the generated stubs; SHEETMESH_TEST_POSTGRES_FILE: the test
cluster's connection string, from tools/pg_cluster.sh; exits 77, skipped, without it.)
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
import time
import unittest

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent / "client" / "python"))
sys.path.insert(0, str(HERE.parent / "testing"))
from ports import wait_port_file  # noqa: E402

SERVER_BIN = PIPELINE_BIN = None
HEARTBEAT = 30  # seconds, ReplicasTest's servers'
CONNINFO = None


def cluster_conninfo():
    f = os.environ.get("SHEETMESH_TEST_POSTGRES_FILE", "")
    if os.environ.get("SHEETMESH_TEST_POSTGRES"):
        return os.environ["SHEETMESH_TEST_POSTGRES"]
    if f and os.path.exists(f):
        return open(f).read().strip()
    return ""


class Replica:
    def __init__(self, tmp, name, conninfo, root, heartbeat=1):
        self.port_file = tmp / ("%s.port" % name)
        self.log = open(tmp / ("%s.log" % name), "w")
        self.proc = subprocess.Popen(
            [SERVER_BIN, "--address=127.0.0.1:0", "--data_dir=%s" % (tmp / "shared"),
             "--scratch_dir=%s" % (tmp / ("scratch-" + name)), "--postgres=%s" % conninfo,
             "--port_file=%s" % self.port_file, "--allowed_root=%s" % root, "--workers=1",
             "--lease_seconds=3", "--heartbeat_seconds=%d" % heartbeat],
            stdout=subprocess.DEVNULL, stderr=self.log)
        wait_port_file(self.port_file, self.proc, "replica " + name, log=tmp / ("%s.log" % name))
        from sheetmesh_client import SheetmeshClient
        self.client = SheetmeshClient("127.0.0.1:%s" % self.port_file.read_text().strip())

    def stop(self, sig=signal.SIGTERM):
        self.client.close()
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            self.proc.wait(timeout=60)
        self.log.close()


class ReplicasTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        from sheetmesh.v1 import jobs_pb2
        cls.pb = jobs_pb2
        cls.tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_replicas_"))
        cls.root = cls.tmp / "root"
        cls.root.mkdir()
        cls.db = "replicas_%d" % os.getpid()
        subprocess.run(["psql", CONNINFO, "-q", "-c", "CREATE DATABASE %s" % cls.db], check=True)
        cls.conninfo = "%s dbname=%s" % (CONNINFO, cls.db)
        cls.sample = cls.root / "rock_128x112x96_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--preset=sample", "-o", str(cls.sample)], check=True,
                       stdout=subprocess.DEVNULL)
        cls.slow = cls.root / "slow_384x384x384_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--dims=384x384x384", "--seed=14", "-o", str(cls.slow)],
                       check=True, stdout=subprocess.DEVNULL)
        # A long heartbeat: a watch through the replica a job's worker does not report to
        # hears of it from the other's events (NOTIFY), not from its heartbeat.
        cls.a = Replica(cls.tmp, "a", cls.conninfo, cls.root, heartbeat=HEARTBEAT)
        cls.b = Replica(cls.tmp, "b", cls.conninfo, cls.root, heartbeat=HEARTBEAT)

    @classmethod
    def tearDownClass(cls):
        for r in (cls.a, cls.b):
            r.stop()
        subprocess.run(["psql", CONNINFO, "-q", "-c", "DROP DATABASE %s WITH (FORCE)" % cls.db])
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def wait_state(self, client, name, states, timeout=120):
        deadline = time.time() + timeout
        while True:
            job = client.get_job(name)
            if job.state in states:
                return job
            self.assertLess(time.time(), deadline, "%s stayed %s" % (name, self.pb.JobState.Name(job.state)))
            time.sleep(0.05)

    def test_a_jobs_on_either_replica_run_once_and_are_seen_by_both(self):
        def one(i):
            mine, other = (self.a, self.b) if i % 2 else (self.b, self.a)
            rid = "replicated-%d" % i
            job = mine.client.create_job(volume_path=str(self.sample), parameters={"r": 5 + i % 3, "labels": [255]},
                                         request_id=rid, no_cache=True)
            again = other.client.create_job(volume_path=str(self.sample), parameters={"r": 5 + i % 3, "labels": [255]},
                                            request_id=rid, no_cache=True)
            self.assertEqual(again.name, job.name, "one request is one job on both replicas")
            done = other.client.watch(job.name)  # watched through the other replica
            return done

        with concurrent.futures.ThreadPoolExecutor(4) as pool:
            jobs = list(pool.map(one, range(12)))
        for job in jobs:
            self.assertEqual(job.state, self.pb.SUCCEEDED, job.error.message)
            self.assertEqual(job.attempts, 1, "%s ran %d times" % (job.name, job.attempts))
            report = next(a for a in job.artifacts if a.name == "report.json")
            out = self.tmp / ("%s.json" % job.name.replace("/", "-"))
            # Downloaded from both replicas: one blob folder, the digest right.
            for r in (self.a, self.b):
                r.client.download(report.digest, str(out))
                self.assertEqual(hashlib.sha256(out.read_bytes()).hexdigest(), report.digest.hash)
        listed = {j.name for j in self.a.client.list_jobs()}
        self.assertTrue({j.name for j in jobs} <= listed)

    def test_b_a_cancel_sent_to_one_replica_stops_the_job_on_the_other(self):
        # b's worker busy first, so that the job runs on a's.
        busy = self.b.client.create_job(volume_path=str(self.slow), parameters={"extract": True, "r": 6}, no_cache=True)
        self.wait_state(self.b.client, busy.name, {self.pb.RUNNING})
        job = self.a.client.create_job(volume_path=str(self.slow), parameters={"extract": True}, no_cache=True)
        self.wait_state(self.a.client, job.name, {self.pb.RUNNING})
        time.sleep(1)
        t = time.time()
        self.b.client.cancel_job(job.name)
        end = self.wait_state(self.a.client, job.name, {self.pb.CANCELLED, self.pb.SUCCEEDED, self.pb.FAILED}, 60)
        took = time.time() - t
        self.assertEqual(end.state, self.pb.CANCELLED, end.error.message)
        # How fast is a benchmark's question (bench/scaleout_bench.py --only cancel), not a test's.
        print("cancel through the other replica took %.2f s" % took)
        self.b.client.cancel_job(busy.name)
        self.wait_state(self.b.client, busy.name, {self.pb.CANCELLED, self.pb.SUCCEEDED}, 60)

    def test_b2_watches_on_both_replicas_hear_every_stage_and_the_end_of_a_job_run_by_either(self):
        job = self.a.client.create_job(volume_path=str(self.sample), parameters={"r": 6, "labels": [255]},
                                       no_cache=True)

        def follow(replica):
            told = []  # stages told by a message that is not a heartbeat

            def on(j, heartbeat):
                if not heartbeat and j.state == self.pb.RUNNING and j.progress.stage:
                    told.append((j.progress.stage_index, j.progress.stage))
            end = replica.client.watch(job.name, on_update=on)
            return end, time.time(), told

        with concurrent.futures.ThreadPoolExecutor(2) as pool:
            fa, fb = pool.submit(follow, self.a), pool.submit(follow, self.b)
            (end_a, t_a, told_a), (end_b, t_b, told_b) = fa.result(), fb.result()
        for end in (end_a, end_b):
            self.assertEqual(end.state, self.pb.SUCCEEDED, end.error.message)
        # Both watches ended when the job did, not one of them a heartbeat later.
        self.assertLess(abs(t_a - t_b), HEARTBEAT / 2, "a watch waited for its heartbeat")
        # Both were told the stages as they came, not at a heartbeat (without the other
        # server's events a watch there hears nothing but heartbeats until the end). The
        # replica that was not told by the worker reads the job from the database, which can
        # be a stage ahead of the events it has applied: a stage that starts and ends
        # between two of its looks may go untold there.
        print("told through a: %s\ntold through b: %s" % (told_a, told_b))
        for told in (told_a, told_b):
            self.assertGreaterEqual(len({i for i, _ in told}), 3, told)

    def test_c_a_job_whose_server_is_killed_runs_on_the_other(self):
        # Only replica a's worker is idle when the job comes: make b busy first.
        busy = self.b.client.create_job(volume_path=str(self.slow), parameters={"extract": True, "r": 6}, no_cache=True)
        self.wait_state(self.b.client, busy.name, {self.pb.RUNNING})
        job = self.a.client.create_job(volume_path=str(self.slow), parameters={"extract": True}, no_cache=True)
        self.wait_state(self.b.client, job.name, {self.pb.RUNNING})
        self.a.stop(signal.SIGKILL)
        t = time.time()
        end = self.wait_state(self.b.client, job.name, {self.pb.SUCCEEDED, self.pb.FAILED, self.pb.CANCELLED}, 240)
        self.assertEqual(end.state, self.pb.SUCCEEDED, end.error.message)
        self.assertEqual(end.attempts, 2, "run again once after its server died")
        print("the killed server's job ended SUCCEEDED on the other %.1f s after the kill" % (time.time() - t))
        self.assertEqual(self.wait_state(self.b.client, busy.name, {self.pb.SUCCEEDED}, 240).attempts, 1)
        type(self).a = Replica(self.tmp, "a2", self.conninfo, self.root, heartbeat=HEARTBEAT)  # for tearDown


class PostgresOutageTest(unittest.TestCase):
    """The database goes away under a running server and comes back (a cluster of its own)."""

    def test_calls_are_unavailable_while_it_is_gone_and_work_again_after(self):
        import grpc
        tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_pg_outage_"))
        tmp.chmod(0o755)  # the cluster's user must reach its folder
        script = HERE.parent.parent / "tools" / "pg_cluster.sh"
        conninfo = subprocess.run(["bash", str(script), "start", str(tmp / "pg")], check=True,
                                  capture_output=True, text=True).stdout.strip()
        root = tmp / "root"
        root.mkdir()
        server = None
        try:
            server = Replica(tmp, "s", conninfo, root)
            volume = root / "rock_64x64x64_u8.raw"
            subprocess.run([PIPELINE_BIN, "phantom", "--dims=64x64x64", "-o", str(volume)], check=True,
                           stdout=subprocess.DEVNULL)
            first = server.client.create_job(volume_path=str(volume), parameters={"r": 5})
            server.client.watch(first.name)
            subprocess.run(["bash", str(script), "stop", str(tmp / "pg")], check=True)
            with self.assertRaises(grpc.RpcError) as e:
                server.client.get_job(first.name)
            self.assertEqual(e.exception.code(), grpc.StatusCode.UNAVAILABLE)
            self.assertIn("PostgreSQL at 127.0.0.1:", e.exception.details())
            self.assertEqual(server.proc.poll(), None, "the server stays up")
            subprocess.run(["bash", str(script), "restart", str(tmp / "pg")], check=True)
            deadline = time.time() + 30
            while True:
                try:
                    again = server.client.get_job(first.name)
                    break
                except grpc.RpcError as err:
                    self.assertLess(time.time(), deadline, err.details())
                    time.sleep(0.2)
            self.assertEqual(again.name, first.name, "nothing lost")
        finally:
            if server:
                server.stop()
            subprocess.run(["bash", str(script), "stop", str(tmp / "pg")])
            shutil.rmtree(tmp, ignore_errors=True)

    def test_an_unreachable_database_at_start_is_a_clear_error(self):
        tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_pg_none_"))
        try:
            out = subprocess.run([SERVER_BIN, "--data_dir=%s" % tmp, "--address=127.0.0.1:0",
                                  "--postgres=host=127.0.0.1 port=1 dbname=sheetmesh connect_timeout=2"],
                                 capture_output=True, text=True, timeout=60)
            self.assertNotEqual(out.returncode, 0)
            self.assertIn("PostgreSQL at 127.0.0.1:1 (database sheetmesh) is unreachable", out.stderr)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    SERVER_BIN, PIPELINE_BIN = sys.argv[1:3]
    del sys.argv[1:3]
    CONNINFO = cluster_conninfo()
    if not CONNINFO:
        print("SKIP: no PostgreSQL test cluster (SHEETMESH_TEST_POSTGRES_FILE; tools/pg_cluster.sh starts one)")
        sys.exit(77)
    sys.path.insert(0, os.environ.get("SHEETMESH_PYTHON_STUBS", ""))
    unittest.main(verbosity=2)
