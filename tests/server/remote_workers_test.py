#!/usr/bin/python3
"""sheetmesh-worker processes against a real sheetmesh-server (no workers of its own) on
loopback: uploaded and shared-storage volumes run remotely with their progress streamed
(a job run as bricks on an upload reads one copy of it per worker),
artifacts come back digest-checked, a cancel stops a remote job, a SIGKILLed worker's job
runs again elsewhere, a draining worker gives its job back, and wrong tokens or a finish
without the lease are refused.

    /usr/bin/python3 tests/server/remote_workers_test.py SERVER_BIN WORKER_BIN PIPELINE_BIN
(SHEETMESH_PYTHON_STUBS: the generated stubs.)
"""

import hashlib
import json
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

SERVER_BIN = WORKER_BIN = PIPELINE_BIN = None
TOKEN, WORKER_TOKEN = "tenant-token", "worker-token"


class RemoteWorkersTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        import grpc
        from sheetmesh_client import SheetmeshClient
        from sheetmesh.v1 import jobs_pb2, workers_pb2, workers_pb2_grpc
        cls.grpc, cls.pb, cls.wpb, cls.wgrpc = grpc, jobs_pb2, workers_pb2, workers_pb2_grpc
        cls.tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_remote_"))
        cls.root = cls.tmp / "root"
        cls.root.mkdir()
        (cls.tmp / "tokens").write_text("%s lab\n" % TOKEN)
        (cls.tmp / "worker_token").write_text(WORKER_TOKEN + "\n")
        (cls.tmp / "wrong_token").write_text("not-it\n")
        cls.sample = cls.root / "rock_128x112x96_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--preset=sample", "-o", str(cls.sample)], check=True,
                       stdout=subprocess.DEVNULL)
        cls.slow = cls.root / "slow_384x384x384_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--dims=384x384x384", "--seed=14", "-o", str(cls.slow)],
                       check=True, stdout=subprocess.DEVNULL)
        cls.log = open(cls.tmp / "server.log", "w")
        cls.server = subprocess.Popen(
            [SERVER_BIN, "--address=127.0.0.1:0", "--data_dir=%s" % (cls.tmp / "data"),
             "--port_file=%s" % (cls.tmp / "port"), "--allowed_root=%s" % cls.root, "--local_workers=false",
             "--auth_token_file=%s" % (cls.tmp / "tokens"), "--worker_token_file=%s" % (cls.tmp / "worker_token"),
             "--lease_seconds=3", "--heartbeat_seconds=1"], stdout=subprocess.DEVNULL, stderr=cls.log)
        wait_port_file(cls.tmp / "port", cls.server, "sheetmesh-server", log=cls.tmp / "server.log")
        cls.address = "127.0.0.1:%s" % (cls.tmp / "port").read_text().strip()
        cls.client = SheetmeshClient(cls.address, token=TOKEN)
        cls.workers = {}
        for name in ("w1", "w2"):
            cls.start_worker(name)

    @classmethod
    def start_worker(cls, name, token="worker_token", wait=True):
        log = open(cls.tmp / ("%s.log" % name), "w")
        proc = subprocess.Popen(
            [WORKER_BIN, "--server=%s" % cls.address, "--token_file=%s" % (cls.tmp / token),
             "--scratch_dir=%s" % (cls.tmp / ("scratch-" + name)), "--allowed_root=%s" % cls.root,
             "--workers=1", "--renew_seconds=1", "--drain_seconds=0", "--name=%s" % name],
            stdout=subprocess.DEVNULL, stderr=log)
        cls.workers[name] = (proc, log)
        return proc

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        for proc, log in cls.workers.values():
            if proc.poll() is None:
                proc.terminate()
                proc.wait(timeout=60)
            log.close()
        cls.server.terminate()
        cls.server.wait(timeout=60)
        cls.log.close()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def wait_state(self, name, states, timeout=180):
        deadline = time.time() + timeout
        while True:
            job = self.client.get_job(name)
            if job.state in states:
                return job
            self.assertLess(time.time(), deadline, "%s stayed %s" % (name, self.pb.JobState.Name(job.state)))
            time.sleep(0.05)

    def test_a_jobs_run_remotely_with_progress_and_their_artifacts(self):
        digest = self.client.upload(str(self.sample))
        jobs = []
        for i in range(4):
            jobs.append(self.client.create_job(volume_digest=digest, file_name=self.sample.name,
                                               parameters={"r": 5 + i, "labels": [255]}, no_cache=True))
            jobs.append(self.client.create_job(volume_path=str(self.sample),
                                               parameters={"r": 5 + i, "labels": [255], "extract": True},
                                               no_cache=True))
        stages = []
        first = self.client.watch(jobs[0].name, on_update=lambda j, hb: stages.append(j.progress.stage_index))
        self.assertEqual(first.state, self.pb.SUCCEEDED, first.error.message)
        self.assertTrue(any(s > 0 for s in stages), "no progress streamed from the remote worker")
        for j in jobs:
            done = self.client.watch(j.name)
            self.assertEqual(done.state, self.pb.SUCCEEDED, done.error.message)
            self.assertEqual(done.attempts, 1)
            names = {a.name for a in done.artifacts}
            self.assertIn("report.json", names)
            for a in done.artifacts:
                out = self.tmp / "download.bin"
                self.client.download(a.digest, str(out))
                self.assertEqual(hashlib.sha256(out.read_bytes()).hexdigest(), a.digest.hash, a.name)

    def test_a_bricked_job_on_an_upload_fetches_only_each_bricks_bytes(self):
        digest = self.client.upload(str(self.sample))
        params = {"r": 5, "labels": [255]}
        # The one-process job reads the file by its path, so that no worker holds the upload
        # whole: the bricked job's plan and bricks fetch what they read.
        one = self.client.create_job(volume_path=str(self.sample), parameters=params, no_cache=True)
        bricked = self.client.create_job(volume_digest=digest, file_name=self.sample.name, parameters=params,
                                         no_cache=True, bricks="128x112x12")
        done = self.client.watch(bricked.name)
        first = self.client.watch(one.name)
        self.assertEqual(done.state, self.pb.SUCCEEDED, done.error.message)
        self.assertEqual(done.bricks.count, 8)
        same = {a.name: a.digest.hash for a in done.artifacts}["surface.ply"]
        self.assertEqual(same, {a.name: a.digest.hash for a in first.artifacts}["surface.ply"])
        # Each worker kept the bytes of the slabs it ran, in a file as large as the upload,
        # with their list, for its next brick; no worker fetched the upload whole, no byte was
        # fetched twice; no job's input folder is left behind.
        fetched = 0
        for name in ("w1", "w2"):
            scratch = self.tmp / ("scratch-" + name)
            cache = scratch / "cache"
            cached = sorted(p.name for p in cache.iterdir()) if cache.exists() else []
            self.assertIn(cached, ([], [digest.hash + ".part", digest.hash + ".ranges"]), name)
            if cached:
                self.assertEqual((cache / (digest.hash + ".part")).stat().st_size, digest.size_bytes)
                ranges = [tuple(map(int, l.split())) for l in
                          (cache / (digest.hash + ".ranges")).read_text().splitlines()]
                fetched += sum(n for _, n in ranges)
            inputs = scratch / "inputs"
            self.assertEqual(list(inputs.iterdir()) if inputs.exists() else [], [])
        print("the workers fetched %d of the upload's %d bytes" % (fetched, digest.size_bytes))
        self.assertGreater(fetched, 0)
        self.assertLessEqual(fetched, digest.size_bytes)

    def test_a_files_of_one_volume_are_laid_out_on_the_worker(self):
        # A folder of TIFF slices and a detached NRRD header with its data file, uploaded
        # as manifests: the remote worker downloads each file into a folder of its own.
        slices = self.tmp / "slices"
        subprocess.run([PIPELINE_BIN, "convert", str(self.sample), "-o", str(slices), "--out_format=tiff-folder"],
                       check=True, capture_output=True)
        folder = self.client.upload_volume_files(slices)
        self.assertEqual(len(folder.files), 96)
        # Slices alike (empty ones) are one blob.
        self.assertEqual(self.client.last_files_sent, len({f.digest.hash for f in folder.files}))
        self.client.upload_volume_files(slices)
        self.assertEqual(self.client.last_files_sent, 0, "stored slices were sent again")
        header = self.tmp / "rock.nhdr"
        header.write_text("NRRD0004\ntype: uint8\ndimension: 3\nsizes: 128 112 96\nencoding: raw\n"
                          "data file: data/rock.raw\n")
        nrrd = self.client.upload_volume_files({"rock.nhdr": header, "data/rock.raw": self.sample},
                                               main="rock.nhdr")
        reports = []
        for files, name in ((folder, "slices"), (nrrd, "rock.nhdr")):
            job = self.client.create_job(volume_files=files, file_name=name,
                                         parameters={"r": 5, "labels": [255]}, no_cache=True)
            done = self.client.watch(job.name)
            self.assertEqual(done.state, self.pb.SUCCEEDED, done.error.message)
            report = next(a for a in done.artifacts if a.name == "report.json")
            out = self.tmp / ("%s.json" % name)
            self.client.download(report.digest, str(out))
            reports.append(json.loads(out.read_text()))
        self.assertEqual(reports[0]["input"]["format"], "tiff-folder")
        self.assertEqual(reports[0]["similarity"], reports[1]["similarity"])

    def test_b_a_cancel_stops_the_remote_job(self):
        job = self.client.create_job(volume_path=str(self.slow), parameters={"extract": True}, no_cache=True)
        self.wait_state(job.name, {self.pb.RUNNING})
        time.sleep(1)
        t = time.time()
        self.client.cancel_job(job.name)
        end = self.wait_state(job.name, {self.pb.CANCELLED, self.pb.SUCCEEDED, self.pb.FAILED}, 60)
        self.assertEqual(end.state, self.pb.CANCELLED, end.error.message)
        print("a cancel stopped the remote job in %.2f s" % (time.time() - t))

    def test_c_a_killed_worker_s_job_runs_on_the_other(self):
        # w2 busy first, so that w1 takes the job; then w1 dies.
        busy = self.client.create_job(volume_path=str(self.slow), parameters={"extract": True, "r": 6}, no_cache=True)
        self.wait_state(busy.name, {self.pb.RUNNING})
        job = self.client.create_job(volume_path=str(self.slow), parameters={"extract": True}, no_cache=True)
        self.wait_state(job.name, {self.pb.RUNNING})
        victims = [n for n, (p, _) in self.workers.items() if p.poll() is None]
        # Which worker holds it is not told to clients: kill both, bring one back.
        for n in victims:
            self.workers[n][0].send_signal(signal.SIGKILL)
            self.workers[n][0].wait()
        t = time.time()
        self.start_worker("w3")
        end = self.wait_state(job.name, {self.pb.SUCCEEDED, self.pb.FAILED, self.pb.CANCELLED}, 300)
        self.assertEqual(end.state, self.pb.SUCCEEDED, end.error.message)
        self.assertEqual(end.attempts, 2)
        self.assertEqual(self.wait_state(busy.name, {self.pb.SUCCEEDED}, 300).attempts, 2)
        print("the killed workers' jobs ended SUCCEEDED %.1f s after the kill" % (time.time() - t))

    def test_d_a_draining_worker_gives_its_job_back(self):
        job = self.client.create_job(volume_path=str(self.slow), parameters={"extract": True, "r": 7}, no_cache=True)
        self.wait_state(job.name, {self.pb.RUNNING})
        live = [n for n, (p, _) in self.workers.items() if p.poll() is None]
        self.assertEqual(live, ["w3"])
        self.workers["w3"][0].send_signal(signal.SIGTERM)  # --drain_seconds=0
        self.assertEqual(self.workers["w3"][0].wait(timeout=60), 0)
        back = self.wait_state(job.name, {self.pb.QUEUED}, 30)
        self.assertEqual(back.attempts, 0, "a released attempt is not counted")
        self.start_worker("w4")
        self.assertEqual(self.wait_state(job.name, {self.pb.SUCCEEDED}, 300).attempts, 1)

    def test_e_wrong_tokens_and_a_finish_without_the_lease_are_refused(self):
        wrong = self.start_worker("wrong", token="wrong_token")
        self.assertEqual(wrong.wait(timeout=60), 2)
        log = (self.tmp / "wrong.log").read_text()
        self.assertIn("a worker needs the server's worker token", log)
        # A tenant's token is not a worker's.
        channel = self.grpc.insecure_channel(self.address)
        stub = self.wgrpc.WorkerServiceStub(channel)
        with self.assertRaises(self.grpc.RpcError) as e:
            stub.LeaseJob(self.wpb.LeaseJobRequest(worker="x"), metadata=[("authorization", "Bearer " + TOKEN)])
        self.assertEqual(e.exception.code(), self.grpc.StatusCode.UNAUTHENTICATED)
        # A worker that does not hold the job cannot end it; the job stays as it was.
        job = self.client.create_job(volume_path=str(self.sample), parameters={"r": 9, "labels": [255]}, no_cache=True)
        done = self.client.watch(job.name)
        with self.assertRaises(self.grpc.RpcError) as e:
            stub.FinishJob(self.wpb.FinishJobRequest(name=job.name, worker="someone-else", state=self.pb.FAILED),
                           metadata=[("authorization", "Bearer " + WORKER_TOKEN)])
        self.assertEqual(e.exception.code(), self.grpc.StatusCode.FAILED_PRECONDITION)
        self.assertIn("is not running under someone-else", e.exception.details())
        self.assertEqual(self.client.get_job(job.name).state, done.state)
        channel.close()


if __name__ == "__main__":
    SERVER_BIN, WORKER_BIN, PIPELINE_BIN = sys.argv[1:4]
    del sys.argv[1:4]
    sys.path.insert(0, os.environ.get("SHEETMESH_PYTHON_STUBS", ""))
    unittest.main(verbosity=2)
