#!/usr/bin/python3
"""sheetmesh-gateway over a real sheetmesh-server on loopback: every route a browser or
curl uses, with status codes and bodies, errors, the watch to the final state (JSON lines
and Server-Sent Events), a resumed upload and ranged downloads checked against the
artifact's digest.

    /usr/bin/python3 tests/gateway/gateway_test.py SERVER_BIN GATEWAY_BIN PIPELINE_BIN
"""

import hashlib
import http.client
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time
import unittest
import uuid

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / "testing"))
from ports import wait_port_file  # noqa: E402

SERVER_BIN = GATEWAY_BIN = PIPELINE_BIN = None
TOKEN = "gateway-test-token"


def decode_png(data):
    """A PNG decoded by VTK's reader (libpng underneath) to an (h, w, 3) array, top row first."""
    import vtk
    from vtk.util import numpy_support
    reader = vtk.vtkPNGReader()
    reader.SetMemoryBuffer(data)
    reader.SetMemoryBufferLength(len(data))
    reader.Update()
    img = reader.GetOutput()
    w, h, _ = img.GetDimensions()
    arr = numpy_support.vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, -1)
    return arr[::-1, :, :3]  # VTK's first row is the bottom one


class GatewayTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = pathlib.Path(tempfile.mkdtemp(prefix="sheetmesh_gateway_"))
        cls.root = cls.tmp / "root"
        cls.root.mkdir()
        cls.sample = cls.root / "rock_128x112x96_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--preset=sample", "-o", str(cls.sample)], check=True,
                       stdout=subprocess.DEVNULL)
        cls.slow = cls.root / "slow_256x256x256_u8.raw"
        subprocess.run([PIPELINE_BIN, "phantom", "--dims=256x256x256", "--seed=14", "-o", str(cls.slow)],
                       check=True, stdout=subprocess.DEVNULL)
        (cls.tmp / "token").write_text(TOKEN + "\n")
        cls.server = subprocess.Popen(
            [SERVER_BIN, "--address=127.0.0.1:0", "--data_dir=%s" % (cls.tmp / "data"),
             "--port_file=%s" % (cls.tmp / "port"), "--allowed_root=%s" % cls.root, "--workers=1",
             "--max_queued_jobs=1", "--heartbeat_seconds=1", "--auth_token_file=%s" % (cls.tmp / "token")],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        port = wait_port_file(cls.tmp / "port", cls.server, "sheetmesh-server")
        cls.gateway = subprocess.Popen(
            [GATEWAY_BIN, "--listen=127.0.0.1:0", "--server=127.0.0.1:%d" % port,
             "--port_file=%s" % (cls.tmp / "gport"), "--cors_origins=http://front.example", "--max_chunk_mb=1",
             "--body_grace=2s", "--body_idle=3s", "--body_min_kb_per_second=4", "--max_watches_per_client=3"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        cls.port = wait_port_file(cls.tmp / "gport", cls.gateway, "sheetmesh-gateway")

    @classmethod
    def tearDownClass(cls):
        cls.gateway.terminate()
        cls.server.terminate()
        cls.gateway.wait(timeout=30)
        cls.server.wait(timeout=60)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    # --- helpers ------------------------------------------------------------------------

    def request(self, method, path, body=None, headers=None, token=True):
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=120)
        h = dict(headers or {})
        if token:
            h.setdefault("Authorization", "Bearer " + TOKEN)
        if isinstance(body, (dict, list)):
            body = json.dumps(body)
            h.setdefault("Content-Type", "application/json")
        conn.request(method, path, body=body, headers=h)
        resp = conn.getresponse()
        data = resp.read()
        conn.close()
        return resp, data

    def json_call(self, method, path, body=None, status=200, **kw):
        resp, data = self.request(method, path, body, **kw)
        self.assertEqual(resp.status, status, data)
        return json.loads(data) if data else None

    def assert_error(self, resp, data, status, code, *words):
        self.assertEqual(resp.status, status, data)
        self.assertEqual(resp.getheader("Content-Type"), "application/json")
        body = json.loads(data)
        self.assertEqual(body["status"], code, body)
        for w in words:
            self.assertIn(w, body["message"])
        return body

    def upload(self, data, chunk=300_000, stop_after=None):
        digest = hashlib.sha256(data).hexdigest()
        base = "/v1/uploads/%s/blobs/%s/%d" % (uuid.uuid4().hex, digest, len(data))
        offset = 0
        while offset < len(data):
            end = min(len(data), offset + chunk)
            if stop_after is not None and offset >= stop_after:
                return base, digest, offset
            last = end == len(data)
            r = self.json_call("PUT", "%s?offset=%d%s" % (base, offset, "&finish=true" if last else ""),
                               data[offset:end], headers={"Content-Type": "application/octet-stream"})
            offset = int(r["committed_size"])
        return base, digest, offset

    def create(self, **fields):
        body = {"request_id": uuid.uuid4().hex}
        body.update(fields)
        return self.json_call("POST", "/v1/jobs", body)

    def watch_lines(self, name):
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=300)
        conn.request("GET", "/v1/%s:watch" % name, headers={"Authorization": "Bearer " + TOKEN})
        resp = conn.getresponse()
        self.assertEqual(resp.status, 200)
        self.assertEqual(resp.getheader("Content-Type"), "application/x-ndjson")
        states = []
        for line in resp:
            if line.strip():
                msg = json.loads(line)
                self.assertNotIn("error", msg)
                states.append(msg["result"]["job"]["state"])
        conn.close()
        return states

    def check_previews(self, job, report):
        """The PNG previews exist, decode, have the size the report states, their phase
        pixels are the sample's phase in that slice, and a legend is drawn below it."""
        arts = {a["name"]: a for a in job["artifacts"]}
        previews = {p["file"]: p for p in report["previews"]}
        self.assertEqual(set(previews), {"preview_slice_x.png", "preview_slice_y.png", "preview_slice_z.png",
                                         "preview_thickness.png"})
        volume = np.fromfile(self.sample, dtype=np.uint8).reshape(96, 112, 128) == 255  # (z, y, x)
        for name, p in previews.items():
            self.assertEqual(arts[name]["media_type"], "image/png")
            resp, data = self.request("GET", "/v1/%s/artifacts/%s" % (job["name"], name))
            self.assertEqual((resp.status, resp.getheader("Content-Type")), (200, "image/png"))
            img = decode_png(data)
            self.assertEqual(img.shape, (p["height"], p["width"], 3), name)
            if p["kind"] != "slice":
                self.assertGreater(len(np.unique(img.reshape(-1, 3), axis=0)), 3, "a blank thickness map")
                continue
            axis = "xyz".index(p["axis"])
            cut = np.take(volume, p["index"], axis=2 - axis)  # 2-D, (rows, cols) in (z|y, y|x) order
            if p["rows_upward"]:
                cut = cut[::-1]
            k = int(p["pixels_per_voxel"])
            truth = np.repeat(np.repeat(cut, k, axis=0), k, axis=1)
            colours = p["colours"]
            # The slice on top, the legend below it (the picture as wide as either needs).
            legend = img[p["slice_height"]:]
            img = img[:truth.shape[0], :truth.shape[1]]
            self.assertTrue(np.any(np.all(legend == colours["phase"], axis=2)), "%s: no legend" % name)
            drawn = np.all(img == colours["mid_surface"], axis=2) | np.all(img == colours["prism_wall"], axis=2)
            shown = np.all(img == colours["phase"], axis=2)
            background = np.all(img == colours["background"], axis=2)
            self.assertTrue(np.all(shown | background | drawn), name)
            self.assertTrue(np.array_equal(shown[~drawn], truth[~drawn]), name)
            self.assertGreater(shown.sum(), 0, name)
            self.assertGreater(drawn.sum(), 0, "%s: no cross-section drawn" % name)

    def cancel_all(self):
        for j in self.json_call("GET", "/v1/jobs?page_size=1000")["jobs"]:
            if j["state"] in ("QUEUED", "RUNNING"):
                self.json_call("POST", "/v1/%s:cancel" % j["name"], {})
        deadline = time.time() + 120
        while any(j["state"] in ("QUEUED", "RUNNING") for j in self.json_call("GET", "/v1/jobs")["jobs"]):
            self.assertLess(time.time(), deadline, "jobs did not end after cancel")
            time.sleep(0.2)

    # --- tests --------------------------------------------------------------------------

    def test_a_mesh_job_end_to_end(self):
        """Resumed upload, job from the digest, watch to SUCCEEDED, downloads whole and ranged."""
        data = self.sample.read_bytes()
        base, digest, stopped = self.upload(data, stop_after=600_000)
        self.assertEqual(stopped, 600_000)
        status = self.json_call("GET", base + ":status")
        self.assertEqual(int(status["committed_size"]), 600_000)
        self.assertFalse(status["complete"])
        # A chunk beyond the committed size is refused, naming the offset; one that overlaps
        # it (a chunk sent again after a break) adds only what is new.
        resp, body = self.request("PUT", base + "?offset=900000", data[900_000:1_000_000])
        self.assert_error(resp, body, 400, "INVALID_ARGUMENT", "write_offset 900000")
        r = self.json_call("PUT", base + "?offset=500000", data[500_000:700_000])
        self.assertEqual(int(r["committed_size"]), 700_000)
        offset = 700_000
        while offset < len(data):
            end = min(len(data), offset + 300_000)
            r = self.json_call("PUT", "%s?offset=%d%s" % (base, offset, "&finish=true" if end == len(data) else ""),
                               data[offset:end])
            offset = int(r["committed_size"])
        self.assertTrue(r["complete"])
        self.assertEqual(offset, len(data))
        missing = self.json_call("POST", "/v1/blobs:findMissing",
                                 {"digests": [{"hash": digest, "size_bytes": len(data)}]})
        self.assertEqual(missing["missing"], [])

        job = self.create(input={"volume_digest": {"hash": digest, "size_bytes": str(len(data))},
                                 "file_name": self.sample.name},
                          parameters={"labels": [255], "r": 7})
        self.assertTrue(job["name"].startswith("jobs/"))
        states = self.watch_lines(job["name"])
        self.assertEqual(states[-1], "SUCCEEDED", states)
        job = self.json_call("GET", "/v1/" + job["name"])
        arts = {a["name"]: a for a in job["artifacts"]}
        self.assertIn("report.json", arts)

        # The whole artifact: raw bytes, its type, length, name, and the digest matches.
        rep = arts["report.json"]
        resp, body = self.request("GET", "/v1/%s/artifacts/report.json" % job["name"])
        self.assertEqual(resp.status, 200)
        self.assertEqual(resp.getheader("Content-Type"), "application/json")
        self.assertEqual(int(resp.getheader("Content-Length")), int(rep["digest"]["size_bytes"]))
        self.assertEqual(resp.getheader("Content-Disposition"), 'attachment; filename=report.json')
        self.assertEqual(hashlib.sha256(body).hexdigest(), rep["digest"]["hash"])
        report = json.loads(body)
        self.assertIn("similarity", report)

        # Ranges: the pieces put together are the artifact.
        ply = arts["surface.ply"]
        size = int(ply["digest"]["size_bytes"])
        parts = []
        for first, last in ((0, 999), (1000, size // 2), (size // 2 + 1, size - 1)):
            resp, part = self.request("GET", "/v1/%s/artifacts/surface.ply" % job["name"],
                                      headers={"Range": "bytes=%d-%d" % (first, last)})
            self.assertEqual(resp.status, 206)
            self.assertEqual(resp.getheader("Content-Range"), "bytes %d-%d/%d" % (first, last, size))
            self.assertEqual(len(part), last - first + 1)
            parts.append(part)
        self.assertEqual(hashlib.sha256(b"".join(parts)).hexdigest(), ply["digest"]["hash"])
        resp, tail = self.request("GET", "/v1/%s/artifacts/surface.ply" % job["name"],
                                  headers={"Range": "bytes=-100"})
        self.assertEqual((resp.status, tail), (206, b"".join(parts)[-100:]))
        resp, body = self.request("GET", "/v1/%s/artifacts/surface.ply" % job["name"],
                                  headers={"Range": "bytes=%d-" % size})
        self.assertEqual(resp.status, 416)
        self.assertEqual(resp.getheader("Content-Range"), "bytes */%d" % size)
        resp, body = self.request("HEAD", "/v1/%s/artifacts/surface.ply" % job["name"])
        self.assertEqual((resp.status, int(resp.getheader("Content-Length")), body), (200, size, b""))
        # A token in a URL is refused; a sealed short-lived link opens one artifact without
        # headers, and only that one.
        resp, body = self.request("GET", "/v1/%s/artifacts/report.json?access_token=%s" % (job["name"], TOKEN),
                                  token=False)
        self.assert_error(resp, body, 400, "INVALID_ARGUMENT", "Authorization")
        link = self.json_call("POST", "/v1/%s/artifacts/report.json:link" % job["name"], {})
        self.assertNotIn(TOKEN, link["url"])
        resp, body = self.request("GET", link["url"], token=False)
        self.assertEqual((resp.status, hashlib.sha256(body).hexdigest()), (200, rep["digest"]["hash"]))
        resp, body = self.request("GET", link["url"].replace("report.json", "surface.ply"), token=False)
        self.assert_error(resp, body, 403, "PERMISSION_DENIED", "report.json")
        resp, body = self.request("POST", "/v1/%s/artifacts/report.json:link" % job["name"], {}, token=False)
        self.assertEqual(resp.status, 401)
        # Range positions past 64 bits are past the end, not ignored.
        resp, body = self.request("GET", "/v1/%s/artifacts/surface.ply" % job["name"],
                                  headers={"Range": "bytes=99999999999999999999-"})
        self.assertEqual(resp.status, 416)
        resp, body = self.request("GET", "/v1/%s/artifacts/surface.ply" % job["name"],
                                  headers={"Range": "bytes=10-99999999999999999999"})
        self.assertEqual((resp.status, len(body)), (206, size - 10))
        resp, body = self.request("GET", "/v1/%s/artifacts/nothing.bin" % job["name"])
        self.assert_error(resp, body, 404, "NOT_FOUND", "nothing.bin", "report.json")

        self.check_previews(job, report)

        # The finished job watched as Server-Sent Events: its state, then the end.
        resp, body = self.request("GET", "/v1/%s:watch" % job["name"], headers={"Accept": "text/event-stream"})
        self.assertEqual(resp.status, 200)
        self.assertEqual(resp.getheader("Content-Type"), "text/event-stream")
        events = [e for e in body.decode().split("\n\n") if e.strip()]
        self.assertTrue(events[0].startswith("event: job\ndata: "), events)
        self.assertEqual(json.loads(events[0].split("data: ", 1)[1])["job"]["state"], "SUCCEEDED")
        self.assertEqual(events[-1], "event: end\ndata: {}")

        # The JSON routes on the finished job: get, list by state, delete, then 404.
        listed = self.json_call("GET", "/v1/jobs?state=SUCCEEDED")
        self.assertIn(job["name"], [j["name"] for j in listed["jobs"]])
        self.json_call("DELETE", "/v1/" + job["name"])
        resp, body = self.request("GET", "/v1/" + job["name"])
        self.assert_error(resp, body, 404, "NOT_FOUND", job["name"])

    def test_b_upload_with_a_wrong_digest_stores_nothing(self):
        data = b"\x01" * 5000
        wrong = hashlib.sha256(b"something else").hexdigest()
        base = "/v1/uploads/%s/blobs/%s/%d" % (uuid.uuid4().hex, wrong, len(data))
        resp, body = self.request("PUT", base + "?finish=true", data)
        self.assert_error(resp, body, 400, "INVALID_ARGUMENT")
        missing = self.json_call("POST", "/v1/blobs:findMissing", {"digests": [{"hash": wrong, "size_bytes": 5000}]})
        self.assertEqual(len(missing["missing"]), 1)
        # A chunk above the gateway's limit (1 MiB here) is refused before it is read.
        base = "/v1/uploads/%s/blobs/%s/%d" % (uuid.uuid4().hex, "0" * 64, 3 << 20)
        resp, body = self.request("PUT", base, b"\0" * (2 << 20))
        self.assert_error(resp, body, 413, "RESOURCE_EXHAUSTED", "--max_chunk_mb")
        resp, body = self.request("PUT", base + "?offset=-4", b"")
        self.assert_error(resp, body, 400, "INVALID_ARGUMENT", "offset=\"-4\"")

    def test_c_errors_map_to_http(self):
        # Bad JSON, an unknown field, a missing field.
        resp, body = self.request("POST", "/v1/jobs", "{not json", headers={"Content-Type": "application/json"})
        self.assert_error(resp, body, 400, "INVALID_ARGUMENT")
        resp, body = self.request("POST", "/v1/jobs", {"request_id": "x", "colour": "red"})
        self.assert_error(resp, body, 400, "INVALID_ARGUMENT", "colour", "sheetmesh.v1.CreateJobRequest")
        resp, body = self.request("POST", "/v1/jobs", {"input": {"volume_path": str(self.sample)}})
        self.assert_error(resp, body, 400, "INVALID_ARGUMENT", "request_id")
        resp, body = self.request("POST", "/v1/jobs", {"request_id": "bad-r", "input": {"volume_path": str(self.sample)},
                                                       "parameters": {"r": -3}})
        self.assert_error(resp, body, 400, "INVALID_ARGUMENT", "-3")
        # Outside the allowed roots, missing, unknown job.
        resp, body = self.request("POST", "/v1/volumes:inspect", {"path": "/etc/passwd"})
        self.assert_error(resp, body, 403, "PERMISSION_DENIED", "path '/etc/passwd'")
        self.assertNotIn("volume_path", json.loads(body)["message"])
        resp, body = self.request("POST", "/v1/volumes:inspect", {"path": str(self.root / "none.raw")})
        self.assert_error(resp, body, 404, "NOT_FOUND")
        inspected = self.json_call("POST", "/v1/volumes:inspect", {"path": str(self.sample)})
        self.assertEqual(inspected["dims"], ["128", "112", "96"])
        resp, body = self.request("GET", "/v1/jobs/no-such-job")
        self.assert_error(resp, body, 404, "NOT_FOUND", "no-such-job")
        resp, body = self.request("GET", "/v1/jobs/no-such-job:watch")
        self.assert_error(resp, body, 404, "NOT_FOUND")
        resp, body = self.request("GET", "/v1/jobs/no-such-job/artifacts/report.json")
        self.assert_error(resp, body, 404, "NOT_FOUND")
        # No token, a wrong token.
        resp, body = self.request("GET", "/v1/jobs", token=False)
        self.assert_error(resp, body, 401, "UNAUTHENTICATED", "bearer token")
        resp, body = self.request("GET", "/v1/jobs", headers={"Authorization": "Bearer nope"})
        self.assert_error(resp, body, 401, "UNAUTHENTICATED")
        # Routes that do not exist, a method a route does not take.
        resp, body = self.request("GET", "/v1/nothing")
        self.assert_error(resp, body, 404, "NOT_FOUND")
        resp, body = self.request("POST", "/v1/jobs/x/artifacts/report.json", {})
        self.assert_error(resp, body, 405, "UNIMPLEMENTED", "GET")

    def test_d_queue_full_is_429_and_running_jobs_conflict(self):
        body = {"input": {"volume_path": str(self.slow)}, "parameters": {"extract": True}, "no_cache": True}
        first = self.create(**body)
        deadline = time.time() + 120
        while self.json_call("GET", "/v1/" + first["name"])["state"] != "RUNNING":
            self.assertLess(time.time(), deadline)
            time.sleep(0.1)
        try:
            self.create(**body)  # queued
            resp, data = self.request("POST", "/v1/jobs", dict(body, request_id=uuid.uuid4().hex))
            self.assert_error(resp, data, 429, "RESOURCE_EXHAUSTED", "max_queued_jobs = 1")
            resp, data = self.request("DELETE", "/v1/" + first["name"])
            self.assert_error(resp, data, 409, "FAILED_PRECONDITION")
            # Its artifacts are not there yet.
            resp, data = self.request("GET", "/v1/%s/artifacts/report.json" % first["name"])
            self.assert_error(resp, data, 409, "FAILED_PRECONDITION", "artifacts come when it has ended")
        finally:
            self.cancel_all()
        self.assertEqual(self.json_call("GET", "/v1/" + first["name"])["state"], "CANCELLED")
        self.assertIn(first["name"], [j["name"] for j in self.json_call("GET", "/v1/jobs?state=CANCELLED")["jobs"]])

    def test_f_the_generated_blob_and_volume_routes(self):
        """ImportVolume, the Write stream as JSON lines, the Read stream as JSON."""
        imported = self.json_call("POST", "/v1/volumes:import", {"path": str(self.sample)})
        data = self.sample.read_bytes()
        self.assertEqual(imported["digest"]["hash"], hashlib.sha256(data).hexdigest())
        resp, body = self.request("POST", "/v1/volumes:import", {"path": "/etc/hostname"})
        self.assert_error(resp, body, 403, "PERMISSION_DENIED", "path '/etc/hostname'")
        # A blob written as newline-delimited WriteRequests (base64 data), read back in pieces.
        blob = bytes(range(256)) * 40
        digest = hashlib.sha256(blob).hexdigest()
        resource = "uploads/%s/blobs/%s/%d" % (uuid.uuid4().hex, digest, len(blob))
        import base64
        lines = [json.dumps({"resource_name": resource, "write_offset": 0,
                             "data": base64.b64encode(blob[:6000]).decode()}),
                 json.dumps({"write_offset": 6000, "finish_write": True,
                             "data": base64.b64encode(blob[6000:]).decode()})]
        written = self.json_call("POST", "/v1/uploads:write", "\n".join(lines),
                                 headers={"Content-Type": "application/x-ndjson"})
        self.assertEqual(int(written["committed_size"]), len(blob))
        resp, body = self.request("GET", "/v1/blobs/%s/%d?read_offset=100&read_limit=1000" % (digest, len(blob)))
        self.assertEqual(resp.status, 200)
        pieces = [json.loads(line)["result"]["data"] for line in body.decode().splitlines() if line.strip()]
        self.assertEqual(b"".join(base64.b64decode(p) for p in pieces), blob[100:1100])
        # A streamed route reports a failure inside the stream, as grpc-gateway does.
        resp, body = self.request("GET", "/v1/blobs/%s/%d" % ("ab" * 32, 5))
        err = json.loads(body.decode().splitlines()[-1])["error"]
        self.assertEqual((err["grpc_code"], err["http_code"]), (5, 404))
        self.assertIn("is not stored", err["message"])

    def test_e_cors_openapi_and_front_end(self):
        resp, body = self.request("OPTIONS", "/v1/jobs", token=False, headers={
            "Origin": "http://front.example", "Access-Control-Request-Method": "POST",
            "Access-Control-Request-Headers": "authorization,content-type"})
        self.assertEqual(resp.status, 204)
        self.assertEqual(resp.getheader("Access-Control-Allow-Origin"), "http://front.example")
        self.assertIn("Authorization", resp.getheader("Access-Control-Allow-Headers"))
        resp, body = self.request("OPTIONS", "/v1/jobs", token=False, headers={
            "Origin": "http://elsewhere.example", "Access-Control-Request-Method": "POST"})
        self.assert_error(resp, body, 403, "PERMISSION_DENIED", "elsewhere.example")
        resp, body = self.request("GET", "/v1/jobs", headers={"Origin": "http://front.example"})
        self.assertEqual(resp.getheader("Access-Control-Allow-Origin"), "http://front.example")
        doc = self.json_call("GET", "/openapi.json", token=False)
        self.assertEqual(doc["swagger"], "2.0")
        for p in ("/v1/jobs", "/v1/jobs/{id}/artifacts/{name}", "/v1/jobs/{id}:watch",
                  "/v1/uploads/{uuid}/blobs/{hash}/{size}", "/v1/volumes:inspect"):
            self.assertIn(p, doc["paths"])
        resp, body = self.request("GET", "/", token=False)
        self.assertEqual(resp.status, 200)
        self.assertIn(b"<title>sheetmesh</title>", body)
        resp, body = self.request("GET", "/jobs/anything", token=False)  # the front-end's own routes
        self.assertIn(b"<title>sheetmesh</title>", body)

    def rss_kb(self):
        for line in open("/proc/%d/status" % self.gateway.pid):
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
        return 0

    def test_g_bodies_are_checked_before_they_are_read(self):
        """Origin and media type first, then the size, then the token; slow bodies are cut."""
        # A text/plain POST (what a cross-site form sends without asking) creates nothing.
        resp, body = self.request("POST", "/v1/jobs", json.dumps({"request_id": "x"}),
                                  headers={"Content-Type": "text/plain"})
        self.assert_error(resp, body, 415, "INVALID_ARGUMENT", "application/json")
        resp, body = self.request("POST", "/v1/jobs", {"request_id": "x"},
                                  headers={"Origin": "http://elsewhere.example"})
        self.assert_error(resp, body, 403, "PERMISSION_DENIED", "elsewhere.example")
        # A name that points here (DNS rebinding): the page's Origin and the Host header agree,
        # but the gateway judges the origin by its own address, not by the request's Host.
        evil = "evil.example:%d" % self.port
        resp, body = self.request("POST", "/v1/jobs", {"request_id": "x"},
                                  headers={"Origin": "http://" + evil, "Host": evil})
        self.assert_error(resp, body, 403, "PERMISSION_DENIED", "evil.example")
        # Its own page, by its address or a loopback name, may.
        for own in ("http://127.0.0.1:%d" % self.port, "http://localhost:%d" % self.port):
            resp, body = self.request("POST", "/v1/jobs", {"request_id": "own"},
                                      headers={"Origin": own})
            self.assertNotEqual(resp.status, 403, body)
        # 256 MiB announced: refused from the headers, the gateway reads none of it.
        before = self.rss_kb()
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=30)
        conn.putrequest("POST", "/v1/jobs")
        for k, v in (("Authorization", "Bearer " + TOKEN), ("Content-Type", "application/json"),
                     ("Content-Length", str(256 << 20))):
            conn.putheader(k, v)
        conn.endheaders()
        conn.send(b"{" + b" " * 65536)
        resp = conn.getresponse()
        self.assert_error(resp, resp.read(), 413, "RESOURCE_EXHAUSTED", str(256 << 20))
        conn.close()
        self.assertLess(self.rss_kb() - before, 20_000, "the gateway grew reading a refused body")
        # Without a token: 401 before the body, for twenty tricklers at once.
        started = time.time()
        conns = []
        for _ in range(20):
            c = http.client.HTTPConnection("127.0.0.1", self.port, timeout=30)
            c.putrequest("POST", "/v1/jobs")
            c.putheader("Content-Type", "application/json")
            c.putheader("Content-Length", "1000")
            c.endheaders()
            c.send(b"{")
            conns.append(c)
        for c in conns:
            resp = c.getresponse()
            self.assertEqual(resp.status, 401)
            resp.read()
            c.close()
        self.assertLess(time.time() - started, 20)
        # ...and the gateway ends the connection instead of waiting for the rest of the body.
        import socket
        s = socket.create_connection(("127.0.0.1", self.port))
        s.sendall(b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Content-Length: 1000\r\n\r\n{")
        s.settimeout(10)
        answer = b""
        while True:
            part = s.recv(65536)  # times out (fails) if the connection is held open
            if not part:
                break
            answer += part
        s.close()
        self.assertTrue(answer.startswith(b"HTTP/1.1 401"), answer[:100])
        # With a token, a body trickling one byte a second is cut off (grace 2 s, 4 KiB/s).
        c = http.client.HTTPConnection("127.0.0.1", self.port, timeout=60)
        c.putrequest("POST", "/v1/jobs")
        for k, v in (("Authorization", "Bearer " + TOKEN), ("Content-Type", "application/json"),
                     ("Content-Length", "100")):
            c.putheader(k, v)
        c.endheaders()
        started = time.time()
        try:
            for _ in range(100):
                c.send(b" ")
                time.sleep(1)
                if time.time() - started > 30:
                    break
            resp = c.getresponse()
            status = resp.status
        except (BrokenPipeError, ConnectionResetError, http.client.RemoteDisconnected):
            status = None  # the gateway closed the connection
        self.assertNotEqual(status, 200)
        self.assertLess(time.time() - started, 15, "the slow body was not cut off")
        c.close()

    def test_h_watches_are_limited_per_client(self):
        job = self.create(input={"volume_path": str(self.slow)}, parameters={"extract": True})
        try:
            streams = []
            for _ in range(3):
                c = http.client.HTTPConnection("127.0.0.1", self.port, timeout=60)
                c.request("GET", "/v1/%s:watch" % job["name"], headers={"Authorization": "Bearer " + TOKEN})
                r = c.getresponse()
                self.assertEqual(r.status, 200)
                r.readline()
                streams.append((c, r))
            resp, body = self.request("GET", "/v1/%s:watch" % job["name"])
            self.assert_error(resp, body, 429, "RESOURCE_EXHAUSTED", "--max_watches_per_client")
            streams[0][0].close()
            deadline = time.time() + 10
            while True:
                c = http.client.HTTPConnection("127.0.0.1", self.port, timeout=60)
                c.request("GET", "/v1/%s:watch" % job["name"], headers={"Authorization": "Bearer " + TOKEN})
                r = c.getresponse()
                if r.status == 200 or time.time() > deadline:
                    break
                r.read()
                c.close()
                time.sleep(0.2)
            self.assertEqual(r.status, 200, "a closed watch frees its place")
            c.close()
            for c, _ in streams[1:]:
                c.close()
        finally:
            self.cancel_all()


if __name__ == "__main__":
    SERVER_BIN, GATEWAY_BIN, PIPELINE_BIN = sys.argv[1:4]
    del sys.argv[1:4]
    unittest.main(verbosity=2)
