// The front-end in a real browser: Debian's Chromium, headless, driven by Playwright,
// against a real sheetmesh-server and sheetmesh-gateway started here. Drops the sample
// volume (its upload resumed from a part sent before), sets r, starts, watches the job to
// SUCCEEDED, checks the numbers shown against report.json, that the 3D view is drawn, and
// that the downloaded report.json has the artifact's digest. Screenshots go to OUT_DIR.
//
//   node web/tests/browser_test.mjs SERVER_BIN GATEWAY_BIN PIPELINE_BIN OUT_DIR
// Exit 0 passed, 1 failed, 77 skipped (Chromium cannot start here).
import { spawn, spawnSync } from "node:child_process";
import { createHash, randomUUID } from "node:crypto";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { chromium } from "playwright-core";

const [serverBin, gatewayBin, pipelineBin, outDir] = process.argv.slice(2);
if (!outDir) {
  console.error("usage: browser_test.mjs SERVER_BIN GATEWAY_BIN PIPELINE_BIN OUT_DIR");
  process.exit(2);
}
const CHROMIUM = process.env.SHEETMESH_CHROMIUM || "/usr/bin/chromium";
const TOKEN = "browser-test-token";
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), "sheetmesh_browser_"));
fs.mkdirSync(outDir, { recursive: true });
const children = [];
let failures = 0;

function check(ok, what) {
  console.log(`${ok ? "ok  " : "FAIL"} ${what}`);
  if (!ok) failures++;
}

function start(bin, args, portFile, what) {
  const child = spawn(bin, args, { stdio: ["ignore", "ignore", "pipe"] });
  let log = "";
  child.stderr.on("data", (d) => { log += d; });
  children.push(child);
  return new Promise((resolve, reject) => {
    const deadline = Date.now() + 60000;
    const poll = () => {
      if (fs.existsSync(portFile) && fs.readFileSync(portFile, "utf8").endsWith("\n")) {
        resolve(Number(fs.readFileSync(portFile, "utf8")));
      } else if (child.exitCode !== null || Date.now() > deadline) {
        reject(new Error(`${what} did not start: ${log}`));
      } else {
        setTimeout(poll, 20);
      }
    };
    poll();
  });
}

async function main() {
  const root = path.join(tmp, "root");
  fs.mkdirSync(root);
  const volume = path.join(root, "rock_128x112x96_u8.raw");
  spawnSync(pipelineBin, ["phantom", "--preset=sample", "-o", volume], { stdio: "ignore" });
  fs.writeFileSync(path.join(tmp, "token"), TOKEN + "\n");
  const port = await start(serverBin, ["--address=127.0.0.1:0", `--data_dir=${tmp}/data`, `--port_file=${tmp}/port`,
    `--allowed_root=${root}`, "--workers=1", "--heartbeat_seconds=1", `--auth_token_file=${tmp}/token`],
  `${tmp}/port`, "sheetmesh-server");
  const gport = await start(gatewayBin, ["--listen=127.0.0.1:0", `--server=127.0.0.1:${port}`, `--port_file=${tmp}/gport`],
    `${tmp}/gport`, "sheetmesh-gateway");
  const base = `http://127.0.0.1:${gport}`;
  const api = (p, init = {}) => fetch(base + p, { ...init, headers: { Authorization: `Bearer ${TOKEN}`, ...(init.headers || {}) } });
  // Pixels of the charts' bar colour (#4a7bd0) on the canvas `selector`: its bars are drawn.
  const barColourPixels = (selector) => page.$eval(selector, (c) => {
    const px = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < px.length; i += 4) n += px[i] === 0x4a && px[i + 1] === 0x7b && px[i + 2] === 0xd0;
    return n;
  });

  let browser;
  try {
    browser = await chromium.launch({ executablePath: CHROMIUM, headless: true,
      args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"] });
  } catch (e) {
    console.log(`SKIP: Chromium (${CHROMIUM}) cannot start here: ${String(e.message).split("\n")[0]}`);
    return 77;
  }
  const page = await (await browser.newContext({ acceptDownloads: true, viewport: { width: 1200, height: 1000 } })).newPage();
  const consoleErrors = [];
  page.on("pageerror", (e) => consoleErrors.push(String(e)));
  page.on("response", (r) => {
    if (r.status() >= 400) console.log(`     (${r.request().method()} ${r.url().replace(base, "")} -> ${r.status()}, auth ${r.request().headers().authorization})`);
  });
  const loadStart = Date.now();
  await page.goto(base + "/");
  await page.waitForSelector("#drop");
  console.log(`front-end loaded in ${Date.now() - loadStart} ms`);

  // Without the token the server's own message shows.
  await page.waitForSelector("#error:not([hidden])", { timeout: 10000 });
  const shown = await page.textContent("#error");
  check(shown.includes("bearer token"), `the server's error is shown: "${shown.trim()}"`);
  await page.fill("#token", TOKEN);
  await page.dispatchEvent("#token", "change");
  await page.waitForSelector("#error[hidden]", { state: "attached" });
  console.log("     token stored:", await page.evaluate(() => localStorage.getItem("sheetmesh.token")));

  // Part of the volume sent before (a broken upload): the drop goes on from there.
  const bytes = fs.readFileSync(volume);
  const hash = createHash("sha256").update(bytes).digest("hex");
  const id = randomUUID().replace(/-/g, "");
  const part = await api(`/v1/uploads/${id}/blobs/${hash}/${bytes.length}?offset=0`, { method: "PUT", body: bytes.subarray(0, 600000) });
  check(part.ok, "a first part of the upload is stored");
  await page.evaluate(([k, v]) => localStorage.setItem(k, v), [`sheetmesh.upload.${hash}.${bytes.length}`, id]);

  // Drop the volume on the drop zone.
  await page.evaluate(([b64, name]) => {
    const bin = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const dt = new DataTransfer();
    dt.items.add(new File([bin], name, { type: "application/octet-stream" }));
    document.getElementById("drop").dispatchEvent(new DragEvent("drop", { dataTransfer: dt, bubbles: true, cancelable: true }));
  }, [bytes.toString("base64"), path.basename(volume)]);
  check((await page.textContent("#chosen")).includes(path.basename(volume)), "the dropped file is taken");
  // The form starts at the parameter table's defaults, as every other interface does.
  const defaults = JSON.parse(spawnSync(pipelineBin, ["params", "--json"], { encoding: "utf8" }).stdout);
  const form = await page.evaluate(() => ({
    r: Number(document.getElementById("budget_value").value),
    labels: document.getElementById("labels").value,
    extract: document.getElementById("extract").checked,
    volume_mesh: document.getElementById("volume_mesh").checked,
  }));
  check(form.r === defaults.r && form.labels === "" && form.extract === defaults.extract &&
    form.volume_mesh === defaults.volume_mesh,
  `the form starts at the table's defaults (${JSON.stringify(form)})`);
  await page.selectOption("#budget", "r");
  await page.fill("#budget_value", "7");
  await page.fill("#labels", "255");
  // Run as bricks: the service's workers read them at once, and every result below is the
  // one process's.
  await page.fill("#bricks", "64");
  await page.screenshot({ path: path.join(outDir, "jobs_page.png"), fullPage: true });
  await page.click("#start");
  await page.waitForFunction(() => location.hash.startsWith("#/jobs/") || !document.getElementById("error").hidden,
    null, { timeout: 60000 });
  const error = await page.$eval("#error", (e) => (e.hidden ? "" : e.textContent));
  check(error === "", `no error after start ${error}`);
  const name = decodeURIComponent(new URL(page.url()).hash.slice(2));
  check(name.startsWith("jobs/"), `the job page opens (${name})`);
  if (!name.startsWith("jobs/")) throw new Error("no job started");
  await page.waitForSelector('#job_state[data-state="SUCCEEDED"]', { timeout: 180000 });
  const bar = await page.getAttribute("#job_head .bar", "aria-valuenow");
  check(bar === "100", `the progress bar reaches 100 (${bar})`);

  const job = await (await api(`/v1/${name}`)).json();
  check(job.state === "SUCCEEDED", "the job SUCCEEDED");
  check(job.bricks && job.bricks.count === 8 && job.bricks.tasks.length === 8,
    `the job ran as 8 bricks (${JSON.stringify(job.bricks && job.bricks.count)})`);
  const rep = job.artifacts.find((a) => a.name === "report.json");
  const report = await (await api(`/v1/${name}/artifacts/report.json`)).json();
  await page.waitForSelector("#numbers");
  for (const [key, value, digits] of [["similarity", report.similarity.similarity, 4], ["dice", report.similarity.dice, 4],
    ["hausdorff", report.similarity.hausdorff_voxels, 2], ["triangles", report.surface.triangles, null]]) {
    const text = (await page.textContent(`#numbers td[data-key="${key}"]`)).trim();
    const want = value === undefined ? "–" : digits === null ? String(value) : Number(value).toFixed(digits);
    check(text === want, `${key} shown ${text}, report.json ${want}`);
  }
  check(await page.isVisible("#histogram"), "the thickness histogram is shown");
  // Its bars hold every triangle of the surface, and they are drawn: pixels of the bars' colour.
  const counts = JSON.parse((await page.getAttribute("#histogram", "data-counts")) || "[]");
  const total = counts.reduce((a, b) => a + b, 0);
  check(total === report.surface.triangles, `the histogram counts ${total} triangles, report.json ${report.surface.triangles}`);
  const barPixels = await barColourPixels("#histogram");
  check(barPixels > 500, `the histogram's bars are drawn (${barPixels} pixels of their colour)`);
  const axis = await page.getAttribute("#histogram", "data-axis");
  check(axis === "aperture per triangle (voxels)", `the histogram says what it counts and in what unit (${axis})`);
  const legend = await page.textContent("#legend3d");
  check(/thickness [0-9.]+ voxels.*[0-9.]+ voxels/.test(legend), `the 3D view has a colour legend with its unit (${legend})`);
  const previews = await page.$$eval(".previews img", (imgs) => imgs.map((i) => i.naturalWidth));
  check(previews.length === 4 && previews.every((w) => w > 0), `four previews load (${previews})`);

  await page.waitForSelector('#view3d[data-ready="1"]', { timeout: 60000 });
  // The 3D view's pixels (a WebGL canvas, copied onto a 2D one to read), as [r, g, b] runs.
  const viewPixels = () => page.$eval("#view3d canvas", (c) => {
    const copy = document.createElement("canvas");
    copy.width = c.width;
    copy.height = c.height;
    const g = copy.getContext("2d");
    g.drawImage(c, 0, 0);
    return Array.from(g.getImageData(0, 0, c.width, c.height).data);
  });
  const px0 = await viewPixels();
  const seen = new Set();
  for (let i = 0; i < px0.length; i += 4 * 7) seen.add((px0[i] << 16) | (px0[i + 1] << 8) | px0[i + 2]);
  const colours = seen.size;
  check(colours > 10, `the 3D view is drawn (${colours} colours)`);
  // The share of the view the mesh covers (pixels off the background).
  const coverage = async () => {
    const px = await viewPixels();
    let off = 0;
    for (let i = 0; i < px.length; i += 4) off += Math.abs(px[i] - 0xf4) + Math.abs(px[i + 1] - 0xf5) + Math.abs(px[i + 2] - 0xf7) > 24;
    return off / (px.length / 4);
  };
  const covered = await coverage();
  check(covered > 0.03, `the surface fills the view (${(100 * covered).toFixed(1)}% of it)`);
  // Turn it with the mouse: the picture changes.
  const before = await page.locator("#view3d canvas").screenshot();
  const box = await page.locator("#view3d canvas").boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 + 120, box.y + box.height / 2 + 40, { steps: 8 });
  await page.mouse.up();
  const after = await page.locator("#view3d canvas").screenshot();
  check(!before.equals(after), "dragging turns the view");
  await page.screenshot({ path: path.join(outDir, "job_page.png"), fullPage: true });

  const [download] = await Promise.all([page.waitForEvent("download"), page.click('#downloads a[data-name="report.json"]')]);
  const saved = path.join(tmp, "report.json");
  await download.saveAs(saved);
  const digest = createHash("sha256").update(fs.readFileSync(saved)).digest("hex");
  check(digest === rep.digest.hash, `the downloaded report.json has the artifact's digest (${digest.slice(0, 12)})`);
  const resumedShown = await page.evaluate(() => sessionStorage.getItem("sheetmesh.last_upload"));
  check(resumedShown !== null && JSON.parse(resumedShown).resumed_from === 600000, `the upload resumed at 600000 (${resumedShown})`);

  // The same volume with a physical voxel size (5 µm): the mesh is in mm, and the view is
  // framed on it as before, not on the voxel counts.
  const physical = await (await api("/v1/jobs", {
    method: "POST", headers: { "Content-Type": "application/json" },
    body: JSON.stringify({
      request_id: randomUUID(),
      input: { volume_digest: { hash, size_bytes: String(bytes.length) }, file_name: path.basename(volume),
        format: { spacing: [0.005, 0.005, 0.005], unit: "mm" } },
      parameters: { r: 7, labels: [255], flow: true },
    }),
  })).json();
  check(typeof physical.name === "string", `a job with a 0.005 mm voxel starts (${JSON.stringify(physical).slice(0, 200)})`);
  await page.goto(`${base}/#/${physical.name}`);
  await page.waitForSelector('#view3d[data-ready="1"]', { timeout: 180000 });
  const coveredPhysical = await coverage();
  const physicalAxis = await page.getAttribute("#histogram", "data-axis");
  const physicalLegend = await page.textContent("#legend3d");
  const piecesHead = await page.textContent("#pieces thead");
  check(physicalAxis === "aperture per triangle (mm)" && /[0-9.]+ mm.*[0-9.]+ mm/.test(physicalLegend) &&
    piecesHead.includes("mean aperture (mm)"),
  `with a 0.005 mm voxel, the histogram, the legend and the pieces table say mm (${physicalAxis}; ${physicalLegend}; ${piecesHead})`);
  // With flow: the tensor as report.json has it, and its bars drawn on a log scale.
  const physicalReport = await (await api(`/v1/${physical.name}/artifacts/report.json`)).json();
  await page.waitForSelector("#permeability_chart", { timeout: 60000 });
  const kxx = (await page.textContent('#permeability td[data-key="k00"]')).trim();
  const wantKxx = Number(physicalReport.flow.permeability_darcy[0][0]).toExponential(3);  // micro-darcy
  check(kxx === wantKxx, `the permeability table's k_xx ${kxx} darcy, report.json ${wantKxx}`);
  const drawn = JSON.parse((await page.getAttribute("#permeability_chart", "data-values")) || "[]");
  // The image's reference runs up to a million voxels (this volume has 1.4 million: skipped,
  // and the table says why).
  const imageRef = physicalReport.flow.image_reference || {};
  const series = imageRef.permeability_m2 ? 3 : 2;
  const ratioRow = await page.textContent("#permeability tbody tr:last-child");
  check(drawn.length === series && drawn[0][3] === physicalReport.flow.principal_darcy[0] &&
    (series === 3 || ratioRow.includes(imageRef.skipped.slice(0, 40))),
  `the chart draws the tensor, the permeameters${series === 3 ? " and the image's" : ""} (${drawn.length} series), the largest principal value first; ${ratioRow.slice(0, 120)}`);
  const kBars = await barColourPixels("#permeability_chart");
  check(kBars > 300, `the tensor's bars are drawn (${kBars} pixels of their colour)`);
  await page.screenshot({ path: path.join(outDir, "job_page_permeability.png"), fullPage: true });
  check(coveredPhysical > 0.5 * covered && coveredPhysical < 2 * covered,
    `with a 0.005 mm voxel the surface fills ${(100 * coveredPhysical).toFixed(1)}% of the view (${(100 * covered).toFixed(1)}% in voxels)`);
  // A job that fails (no voxel has the value 7) looks failed: a red bar and the error.
  const failing = await (await api("/v1/jobs", {
    method: "POST", headers: { "Content-Type": "application/json" },
    body: JSON.stringify({
      request_id: randomUUID(),
      input: { volume_digest: { hash, size_bytes: String(bytes.length) }, file_name: path.basename(volume) },
      parameters: { r: 7, labels: [7] },
    }),
  })).json();
  await page.goto(`${base}/#/${failing.name}`);
  await page.waitForSelector('#job_state[data-state="FAILED"]', { timeout: 120000 });
  const failedFill = await page.$eval("#job_head .bar .fill", (f) => getComputedStyle(f).backgroundColor);
  check(failedFill === "rgb(200, 69, 60)", `a failed job's bar is red (${failedFill})`);
  const failedError = await page.textContent("#job_error");
  check(failedError.includes("7"), `a failed job shows its error (${failedError.slice(0, 120)})`);
  check((await page.$("#downloads")) === null, "a job that failed before any output lists no downloads");
  // A job whose volume stage fails keeps its surface, score and previews: shown and listed.
  const volumeFails = await (await api("/v1/jobs", {
    method: "POST", headers: { "Content-Type": "application/json" },
    body: JSON.stringify({
      request_id: randomUUID(),
      input: { volume_digest: { hash, size_bytes: String(bytes.length) }, file_name: path.basename(volume) },
      parameters: { r: 7, volume_mesh: true, max_tetrahedra: "10" },
    }),
  })).json();
  await page.goto(`${base}/#/${volumeFails.name}`);
  await page.waitForSelector('#job_state[data-state="FAILED"]', { timeout: 180000 });
  await page.waitForSelector("#downloads", { timeout: 60000 });
  const kept = await page.$$eval("#downloads a", (a) => a.map((x) => x.dataset.name));
  const keptText = await page.textContent("#kept");
  check(kept.includes("surface.ply") && kept.includes("report.json") && !kept.includes("volume.vtu") &&
    keptText.includes(`${kept.length} files`), `a failed volume stage lists what it kept (${kept.join(", ")})`);
  await page.waitForSelector('#view3d[data-ready="1"]', { timeout: 60000 });
  check(true, "the kept surface is shown in 3D");
  // A second job on the same volume with extraction and the volume mesh: its pieces table
  // and Table 3's rows as report.json has them (the upload is found complete at once).
  await page.goto(base + "/#/");
  await page.waitForSelector("#drop");
  check((await page.textContent("#chosen")).includes(path.basename(volume)), "the chosen file stays chosen");
  await page.check("#extract");
  await page.check("#volume_mesh");
  await page.click("#start");
  await page.waitForFunction((old) => location.hash !== "#/" + old && location.hash.startsWith("#/jobs/"), name, { timeout: 60000 });
  const second = decodeURIComponent(new URL(page.url()).hash.slice(2));
  await page.waitForSelector('#job_state[data-state="SUCCEEDED"], #job_error', { timeout: 300000 });
  const full = await (await api(`/v1/${second}/artifacts/report.json`)).json();
  await page.waitForSelector("#quality");
  const rows = await page.$$eval("#pieces tbody tr", (r) => r.map((x) => [...x.cells].map((c) => c.textContent)));
  check(rows.length === full.pieces.length && rows.length > 0, `the pieces table has report.json's ${full.pieces.length} pieces (${rows.length})`);
  const p0 = full.pieces[0];
  check(rows[0][4] === Number(p0.dip_degrees).toFixed(1) && rows[0][5] === Number(p0.dip_direction_degrees).toFixed(1),
    `piece ${p0.piece}: dip ${rows[0][4]}, dip direction ${rows[0][5]}`);
  // Each piece as a sheet or a body, and why, as report.json says.
  const reps = (full.representation || {}).pieces || [];
  if (reps.length) {
    const why = await page.$$eval("#representation tbody tr", (r) => r.map((x) => [...x.cells].map((c) => c.textContent)));
    check(why.length === reps.length && why.every((row, i) => row[1] === reps[i].representation && row[2] === reps[i].reason && row[2] !== ""),
      `the sheets-and-bodies table has report.json's ${reps.length} pieces with their reasons (${JSON.stringify(why[0])})`);
  }
  const tets = (await page.textContent('#quality td[data-key="tetrahedra"]')).trim();
  check(tets === String(full.volume_mesh.tetrahedra), `Table 3: ${tets} tetrahedra, report.json ${full.volume_mesh.tetrahedra}`);
  const minDihedral = await page.$eval("#quality tbody tr:nth-child(3) td", (td) => td.textContent);
  check(minDihedral === Number(full.volume_mesh.quality.min_dihedral_degrees.min).toFixed(3), `minimum dihedral ${minDihedral}`);
  await page.waitForSelector('#view3d[data-ready="1"]', { timeout: 60000 });
  const plain = await page.locator("#view3d canvas").screenshot();
  await page.check("#boundary");
  const boxed = await page.locator("#view3d canvas").screenshot();
  check(!plain.equals(boxed), "the volume mesh's boundary shows when ticked");
  await page.screenshot({ path: path.join(outDir, "job_page_volume_mesh.png"), fullPage: true });
  check(consoleErrors.length === 0, `no uncaught errors in the page ${consoleErrors.join("; ")}`);
  await browser.close();
  return failures ? 1 : 0;
}

let code = 1;
try {
  code = await main();
} catch (e) {
  console.error("FAIL", e);
  code = 1;
} finally {
  for (const c of children) c.kill("SIGTERM");
  fs.rmSync(tmp, { recursive: true, force: true });
}
console.log(code === 0 ? "browser test passed" : code === 77 ? "browser test skipped" : `browser test failed (${failures} checks)`);
process.exit(code);
