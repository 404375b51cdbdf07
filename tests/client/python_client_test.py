#!/usr/bin/python3
"""The Python client against a real sheetmesh-server process over loopback.

    /usr/bin/python3 tests/client/python_client_test.py SERVER_BIN PIPELINE_BIN
(with SHEETMESH_PYTHON_STUBS pointing at the build's generated stubs).
"""

import hashlib
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time
import unittest
import warnings

import grpc

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent / "client" / "python"))
import sheetmesh_client  # noqa: E402
from sheetmesh_client import SheetmeshClient, SheetmeshError  # noqa: E402
from sheetmesh.v1 import blobs_pb2, jobs_pb2  # noqa: E402

SERVER_BIN = PIPELINE_BIN = None


class PythonClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_pyclient_"))
        cls.root = cls.tmp / "root"
        cls.root.mkdir()
        port_file = cls.tmp / "port"
        cls.server = subprocess.Popen(
            [SERVER_BIN, "--address=127.0.0.1:0", "--data_dir=%s" % (cls.tmp / "data"),
             "--port_file=%s" % port_file, "--allowed_root=%s" % cls.root, "--workers=2",
             "--heartbeat_seconds=1"],
            stdout=subprocess.DEVNULL)
        deadline = time.time() + 30
        while not (port_file.exists() and port_file.read_text().endswith("\n")):
            if time.time() > deadline or cls.server.poll() is not None:
                raise RuntimeError("sheetmesh-server did not start")
            time.sleep(0.02)
        cls.address = "127.0.0.1:%s" % port_file.read_text().strip()
        cls.client = SheetmeshClient(cls.address)
        cls.volume = cls.root / "rock_64x64x64_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--dims=64x64x64", "--seed=3", "-o", str(cls.volume)],
                       check=True, stdout=subprocess.DEVNULL)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        cls.server.terminate()
        cls.server.wait(timeout=60)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_health(self):
        self.assertEqual(self.client.health(), "SERVING")

    def test_an_unreachable_server_gets_a_hint(self):
        for address, hint in (("127.0.0.1:1", "hint: nothing listens at 127.0.0.1:1"),
                              ("http://127.0.0.1:1", "hint: the address takes HOST:PORT without a scheme"),
                              ("nohost.invalid:5", "hint: the host in nohost.invalid:5 does not resolve")):
            with SheetmeshClient(address) as c:
                with self.assertRaises(grpc.RpcError) as e:
                    c.jobs.ListJobs(jobs_pb2.ListJobsRequest(), timeout=10)
                self.assertTrue(c.hint(e.exception).startswith(hint), (address, c.hint(e.exception)))
        with SheetmeshClient(self.address, tls=True) as c:
            with self.assertRaises(grpc.RpcError) as e:
                c.jobs.ListJobs(jobs_pb2.ListJobsRequest(), timeout=10)
            self.assertIn("does not speak TLS", c.hint(e.exception))
        with self.assertRaises(grpc.RpcError) as e:
            self.client.get_job("jobs/none")
        self.assertEqual(self.client.hint(e.exception), "", "only unreachable servers get a hint")

    def test_mesh_prints_the_stages_on_a_terminal_and_nothing_elsewhere(self):
        import io

        class Terminal(io.StringIO):
            def isatty(self):
                return True

        # (Radii no other test asks for: a job the server has already run comes back done.)
        for stream, out, r in ((Terminal(), "tty_out", 6), (io.StringIO(), "pipe_out", 7)):
            saved, sys.stderr = sys.stderr, stream
            try:
                job = self.client.mesh(self.volume, self.tmp / out, r=r)
            finally:
                sys.stderr = saved
            self.assertEqual(job.state, jobs_pb2.SUCCEEDED)
            lines = stream.getvalue().splitlines()
            if isinstance(stream, Terminal):
                # One line per change, the stages in order, the last the job's end.
                self.assertTrue(any(" RUNNING stage " in x for x in lines), lines)
                self.assertTrue(lines[-1].endswith("SUCCEEDED"), lines)
                self.assertEqual(len(lines), len(set(lines)), lines)
            else:
                self.assertEqual(lines, [])

    def test_mesh_uploads_runs_and_downloads_verified_files(self):
        out = self.tmp / "mesh_out"
        stages = []

        def on_update(job, heartbeat):
            if job.state == jobs_pb2.RUNNING and job.progress.stage_index and (
                    not stages or stages[-1] != job.progress.stage_index):
                stages.append(job.progress.stage_index)

        job = self.client.mesh(self.volume, out, on_update=on_update, r=5)
        self.assertEqual(job.state, jobs_pb2.SUCCEEDED)
        # The watch starts once the job is created, so on a loaded machine the first stage
        # (reading a small volume) may be over before it; from the first stage seen on, every
        # stage is streamed, in order, up to the last.
        self.assertTrue(stages, "no progress streamed")
        self.assertLessEqual(stages[0], 2, stages)
        self.assertEqual(stages, list(range(stages[0], job.progress.stage_count + 1)))
        names = {a.name for a in job.artifacts}
        self.assertTrue({"surface.ply", "report.json"} <= names, names)
        for a in job.artifacts:
            data = (out / a.name).read_bytes()
            self.assertEqual(hashlib.sha256(data).hexdigest(), a.digest.hash, a.name)
        report = json.loads((out / "report.json").read_text())
        self.assertGreater(report["similarity"]["similarity"], 0.3)
        # The same again is answered from the cache.
        again = self.client.create_job(volume_digest=sheetmesh_client.file_digest(self.volume),
                                       file_name=self.volume.name, parameters={"r": 5})
        self.assertEqual(again.state, jobs_pb2.SUCCEEDED)
        self.assertEqual(again.cached_from, job.name)
        listed = [j.name for j in self.client.list_jobs(page_size=1)]
        self.assertIn(job.name, listed)
        self.assertIn(again.name, listed)

    def test_a_volume_mesh_under_its_aim_warns_naming_the_angle(self):
        out = self.tmp / "aim_out"
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            job = self.client.mesh(self.volume, out, r=5, volume_mesh=True, tet_min_dihedral=20)
        self.assertEqual(job.state, jobs_pb2.SUCCEEDED)
        report = json.loads((out / "report.json").read_text())
        worst = report["volume_mesh"]["quality"]["min_dihedral_degrees"]["min"]
        angle = [w for w in caught if issubclass(w.category, sheetmesh_client.AngleWarning)]
        if worst < 20:
            self.assertEqual(len(angle), 1, [str(w.message) for w in caught])
            text = str(angle[0].message)
            self.assertIn("min dihedral %.2f° under tet.min_dihedral = 20°" % worst, text)
            self.assertIn("at voxel (", text)
        else:
            self.assertEqual(angle, [])
        # A surface under the grid floor warns too, exactly when the report says so.
        floor = [w for w in caught if issubclass(w.category, sheetmesh_client.FidelityWarning)]
        if "floor_warning" in report["similarity"]:
            self.assertEqual(len(floor), 1, [str(w.message) for w in caught])
            self.assertIn("is under the grid model's", str(floor[0].message))
        else:
            self.assertEqual(floor, [])

    def test_reference_inside_root_and_refused_outside(self):
        out = self.tmp / "ref_out"
        job = self.client.mesh(self.volume, out, reference=True)
        self.assertEqual(job.state, jobs_pb2.SUCCEEDED)
        outside = self.tmp / "outside_8x8x8_u8.raw"
        outside.write_bytes(bytes(512))
        with self.assertRaises(grpc.RpcError) as e:
            self.client.create_job(volume_path=str(outside))
        self.assertEqual(e.exception.code(), grpc.StatusCode.PERMISSION_DENIED)
        info = self.client.inspect_volume(str(self.volume))
        self.assertEqual(list(info.dims), [64, 64, 64])

    def test_hdf5_dataset_by_reference(self):
        try:
            import h5py
        except ImportError:
            self.skipTest("/usr/bin/python3 has no h5py")
        import numpy as np
        voxels = np.fromfile(self.volume, dtype=np.uint8).reshape(64, 64, 64)
        scan = self.root / "scan.h5"
        with h5py.File(scan, "w") as f:
            d = f.create_dataset("entry/data/data", data=voxels, chunks=(8, 32, 32), compression="gzip")
            d.attrs["element_size_um"] = [2.0, 1.0, 1.0]  # z, y, x
        info = self.client.inspect_volume("%s:/entry/data/data" % scan)
        self.assertEqual(list(info.dims), [64, 64, 64])
        self.assertEqual(list(info.spacing), [1.0, 1.0, 2.0])
        job = self.client.watch(self.client.create_job(volume_path="%s:/entry/data/data" % scan,
                                                       parameters={"r": 5}, no_cache=True).name)
        self.assertEqual(job.state, jobs_pb2.SUCCEEDED, job.error.message)
        # A dataset the file lacks is the reader's NOT_FOUND listing what it has; a file
        # outside the roots is refused before its dataset is looked at.
        job = self.client.watch(self.client.create_job(volume_path="%s:/entry/nope" % scan,
                                                       no_cache=True).name)
        self.assertEqual(job.state, jobs_pb2.FAILED)
        self.assertIn("/entry/data/data", job.error.message)
        shutil.copy(scan, self.tmp / "scan.h5")
        with self.assertRaises(grpc.RpcError) as e:
            self.client.create_job(volume_path="%s:/entry/data/data" % (self.tmp / "scan.h5"))
        self.assertEqual(e.exception.code(), grpc.StatusCode.PERMISSION_DENIED)

    def test_bad_parameters_name_the_field(self):
        digest = self.client.upload(self.volume)
        with self.assertRaises(grpc.RpcError) as e:
            self.client.create_job(volume_digest=digest, file_name=self.volume.name, parameters={"r": -1})
        self.assertEqual(e.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("parameters.r = -1", e.exception.details())

    def test_unknown_fields_and_values_of_the_wrong_type_are_named(self):
        for fields, said in (({"dimz": [64, 64, 64]}, "unknown parameter 'dimz'"),
                             ({"r": "five"}, "parameter r='five'"),
                             ({"dims": "64x64"}, "dims='64x64': give three sizes")):
            with self.assertRaises(ValueError) as e:
                self.client.mesh(self.volume, self.tmp / "never", **fields)
            self.assertIn(said, str(e.exception))
        self.assertFalse((self.tmp / "never").exists())

    def test_mesh_takes_the_volume_format_by_name(self):
        plain = self.tmp / "scan.raw"  # no dims in the name: the format says them
        shutil.copy(self.volume, plain)
        job = self.client.mesh(plain, self.tmp / "named_out", dims="64x64x64", dtype="uint8",
                               spacing=[0.005] * 3, unit="mm", r=5)
        self.assertEqual(job.state, jobs_pb2.SUCCEEDED)
        report = json.loads((self.tmp / "named_out" / "report.json").read_text())
        self.assertEqual(report["input"]["dims"], [64, 64, 64])
        self.assertEqual(report["input"]["unit"], "mm")

    def test_mesh_takes_a_folder_of_slices(self):
        try:
            from PIL import Image
        except ImportError:
            self.skipTest("/usr/bin/python3 has no PIL to write the slices")
        import numpy as np
        voxels = np.fromfile(self.volume, dtype=np.uint8).reshape(64, 64, 64)
        folder = self.tmp / "slices"
        folder.mkdir()
        for z in range(64):
            Image.fromarray(voxels[z]).save(folder / ("s%d.png" % z))
        job = self.client.mesh(folder, self.tmp / "slices_out", r=5)
        self.assertEqual(job.state, jobs_pb2.SUCCEEDED)
        report = json.loads((self.tmp / "slices_out" / "report.json").read_text())
        self.assertEqual(report["input"]["dims"], [64, 64, 64])
        # A missing volume is a FileNotFoundError (as open raises), and a SheetmeshError.
        with self.assertRaises(FileNotFoundError) as e:
            self.client.mesh(self.tmp / "no_such_folder", self.tmp / "never")
        self.assertIsInstance(e.exception, SheetmeshError)
        self.assertEqual(e.exception.filename, str(self.tmp / "no_such_folder"))
        self.assertIn("no such file or folder", str(e.exception))
        self.assertIn("no_such_folder", str(e.exception))
        self.assertFalse((self.tmp / "never").exists())

    def test_failed_job_raises_with_the_readers_message(self):
        junk = self.tmp / "junk.nrrd"
        junk.write_text("NRRD0004\ntype: complex\n\n")
        with self.assertRaises(SheetmeshError) as e:
            self.client.mesh(junk, self.tmp / "junk_out")
        self.assertIn("FAILED", str(e.exception))
        self.assertIn("junk.nrrd", str(e.exception))

    def test_a_failed_volume_stage_raises_with_the_files_it_kept(self):
        out = self.tmp / "kept_out"
        with self.assertRaises(SheetmeshError) as e:
            self.client.mesh(self.volume, out, r=5, volume_mesh=True, max_tetrahedra=10)
        self.assertIn("FAILED", str(e.exception))
        self.assertIn("kept", str(e.exception))
        names = {p.name for p in e.exception.kept}
        self.assertTrue({"surface.ply", "report.json"} <= names, names)
        self.assertNotIn("volume.vtu", names)
        report = json.loads((out / "report.json").read_text())
        self.assertEqual(report["failed"]["stage"], "volume")

    def test_upload_resumes_after_a_broken_stream(self):
        path = self.tmp / "blob.bin"
        data = os.urandom(3 * (1 << 20) + 5)
        path.write_bytes(data)
        digest = sheetmesh_client.file_digest(path)
        resource = "uploads/u%s/blobs/%s/%d" % (digest.hash[:32], digest.hash, digest.size_bytes)

        def two_pieces_then_break():
            for i in range(2):
                yield blobs_pb2.WriteRequest(resource_name=resource if i == 0 else "", write_offset=i << 20,
                                             data=data[i << 20:(i + 1) << 20])
            time.sleep(0.3)
            raise RuntimeError("the connection broke")

        with self.assertRaises(grpc.RpcError):
            self.client.blobs.Write(two_pieces_then_break())
        status = None
        for _ in range(100):
            status = self.client.blobs.QueryWriteStatus(blobs_pb2.QueryWriteStatusRequest(resource_name=resource))
            if status.committed_size == 2 << 20:
                break
            time.sleep(0.05)
        self.assertEqual(status.committed_size, 2 << 20)
        reports = []
        self.client.upload(path, progress=lambda sent, total: reports.append(sent))
        self.assertEqual(reports[0], 3 << 20)  # resumed past what the server held
        back = self.client.download(digest, self.tmp / "back.bin")
        self.assertEqual(back.read_bytes(), data)

    def test_cancel(self):
        big = self.root / "big_192x192x192_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--dims=192x192x192", "--seed=4", "-o", str(big)],
                       check=True, stdout=subprocess.DEVNULL)
        job = self.client.create_job(volume_path=str(big), parameters={"extract": True}, no_cache=True)
        self.client.cancel_job(job.name)
        end = self.client.watch(job.name)
        self.assertEqual(end.state, jobs_pb2.CANCELLED)
        self.client.delete_job(job.name)
        with self.assertRaises(grpc.RpcError) as e:
            self.client.get_job(job.name)
        self.assertEqual(e.exception.code(), grpc.StatusCode.NOT_FOUND)


if __name__ == "__main__":
    SERVER_BIN, PIPELINE_BIN = sys.argv[1], sys.argv[2]
    unittest.main(argv=[sys.argv[0]] + sys.argv[3:], verbosity=2)
