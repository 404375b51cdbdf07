// One job: live progress, then its figures, tables, histogram, 3D view and downloads.
import * as api from "./api.js";
import { faceValues, permeabilityChart, thicknessHistogram } from "./charts.js";
import { el, isTerminal, jobFraction, jobLabel, progressBar, showError } from "./dom.js";

const fmt = (v, d = 4) => (v === undefined || v === null || Number.isNaN(v) ? "–" : Number(v).toFixed(d));

function numbers(report) {
  const s = report.similarity || {};
  const surf = report.surface || {};
  const rows = [
    ["similarity", "similarity", fmt(s.similarity)],
    ["dice", "Dice", fmt(s.dice)],
    ["hausdorff", "Hausdorff (voxels)", fmt(s.hausdorff_voxels, 2)],
    ["triangles", "triangles", surf.triangles ?? "–"],
    ["vertices", "vertices", surf.vertices ?? "–"],
  ];
  return el("table", { id: "numbers", class: "numbers" },
    el("tbody", {}, rows.map(([key, label, v]) => el("tr", {}, el("th", {}, label), el("td", { "data-key": key }, String(v))))));
}

// The report's length unit, for labels: "mm", or "voxels" without a physical size.
function unitOf(report) {
  const input = report.input || {};
  const spacing = input.spacing || [1, 1, 1];
  if (input.unit) return input.unit;
  return spacing.every((s) => s === 1) ? "voxels" : "volume units";
}

// Each piece as a sheet or a body, and why (the report's representation block).
function representationTable(report) {
  const pieces = (report.representation || {}).pieces || [];
  if (!pieces.length) return el("p", {}, "Every piece a sheet (surface.representation = sheet).");
  return el("table", { id: "representation" },
    el("thead", {}, el("tr", {}, ["piece", "as", "why"].map((h) => el("th", {}, h)))),
    el("tbody", {}, pieces.map((p) => el("tr", {},
      el("td", {}, p.part_of >= 0 ? `${p.piece} (a lens of ${p.part_of})` : p.piece),
      el("td", { "data-key": "representation" }, p.representation === "body" && p.equivalent_aperture_voxels
        ? `body (equivalent aperture ${fmt(p.equivalent_aperture_voxels, 3)} voxels)` : p.representation),
      el("td", {}, p.reason || "")))));
}

function piecesTable(report) {
  const pieces = report.pieces || [];
  const unit = unitOf(report);
  if (!pieces.length) return el("p", {}, "No pieces table (run with extraction for dip, dip direction and aperture per piece).");
  return el("table", { id: "pieces" },
    el("thead", {}, el("tr", {}, ["piece", "sheet", "voxels", "triangles", "dip (°)", "dip direction (°)", `mean aperture (${unit})`, `max aperture (${unit})`].map((h) => el("th", {}, h)))),
    el("tbody", {}, pieces.map((p) => el("tr", {},
      el("td", {}, p.piece), el("td", {}, p.sheet ?? ""), el("td", {}, p.voxels), el("td", {}, p.triangles),
      el("td", {}, fmt(p.dip_degrees ?? p.dip, 1)), el("td", {}, fmt(p.dip_direction_degrees ?? p.dip_direction, 1)),
      el("td", {}, fmt(p.mean_aperture, 2)), el("td", {}, fmt(p.max_aperture, 2))))));
}

function qualityTable(report) {
  const vm = report.volume_mesh;
  if (!vm) return el("p", {}, "No volume mesh (tick “volume mesh” to make one).");
  const q = vm.quality || {};
  const row = (label, key) => el("tr", {}, el("th", {}, label),
    el("td", {}, fmt(q[key] && q[key].min, 3)), el("td", {}, fmt(q[key] && q[key].mean, 3)));
  const table = el("table", { id: "quality" },
    el("thead", {}, el("tr", {}, el("th", {}, "Table 3"), el("th", {}, "min"), el("th", {}, "mean"))),
    el("tbody", {},
      el("tr", {}, el("th", {}, "tetrahedra"), el("td", { colspan: 2, "data-key": "tetrahedra" }, String(vm.tetrahedra))),
      el("tr", {}, el("th", {}, "nodes"), el("td", { colspan: 2, "data-key": "nodes" }, String(vm.nodes))),
      row("dihedral angle (°)", "min_dihedral_degrees"), row("radius aspect", "radius_aspect"),
      row("gamma", "gamma"), row("edge aspect", "edge_aspect")));
  // A minimum under tet.min_dihedral is said, with where and why (never silent).
  if (!vm.angle_warning) return table;
  return el("div", {}, table, el("p", { id: "angle-warning", class: "warning" }, `Warning: ${vm.angle_warning.text}`));
}

// The permeability tensor (darcy), its principal values and the mesh / image ratios.
function permeabilityTable(flow) {
  const k = flow.permeability_darcy;
  const g = (v) => {
    if (!Number.isFinite(v)) return "–";
    const a = Math.abs(v);
    return a === 0 || (a >= 1e-3 && a < 1e4) ? Number(v).toPrecision(4) : Number(v).toExponential(3);
  };
  const image = flow.image_reference || {};
  const ratio = image.mesh_to_image_per_axis;
  return el("table", { id: "permeability" },
    el("thead", {}, el("tr", {}, ["tensor (darcy)", "x", "y", "z"].map((h) => el("th", {}, h)))),
    el("tbody", {},
      ["x", "y", "z"].map((a, i) => el("tr", {}, el("th", {}, a), k[i].map((v, j) => el("td", { "data-key": `k${i}${j}` }, g(v))))),
      el("tr", {}, el("th", {}, "principal"), flow.principal_darcy.map((v, i) => el("td", { "data-key": `principal${i}` }, g(v)))),
      el("tr", {}, el("th", {}, "permeameter"), flow.permeameter_darcy.map((v) => el("td", {}, g(v)))),
      ratio ? el("tr", {}, el("th", {}, "mesh / image"), ratio.map((v) => el("td", {}, fmt(v, 3)))) :
        el("tr", {}, el("th", {}, "mesh / image"), el("td", { colspan: 3 }, image.skipped || "–"))));
}

// The 3D view's colours: its thickness range in the volume's unit, blue to red; bodies grey.
function colourLegend(range, unit) {
  const stops = [0, 0.25, 0.5, 0.75, 1].map((t) => `hsl(${Math.round((1 - t) * 0.66 * 360)}, 85%, 50%)`);
  const fmtLen = (v) => (Number.isFinite(v) ? Number(v.toPrecision(3)).toString() : "–");
  return el("div", { id: "legend3d", class: "legend" },
    el("span", {}, `thickness ${fmtLen(range.lo)} ${unit}`),
    el("span", { class: "ramp", style: `background: linear-gradient(to right, ${stops.join(", ")})` }),
    el("span", {}, `${fmtLen(range.hi)} ${unit}`),
    range.bodies ? el("span", { class: "swatch body" }, "") : "",
    range.bodies ? el("span", {}, "bodies (closed surfaces)") : "");
}

// A download through a fresh short-lived link (the token never goes into a URL).
async function download(event, job, name) {
  event.preventDefault();
  try {
    const a = el("a", { href: await api.artifactLink(job, name), download: name });
    document.body.append(a);
    a.click();
    a.remove();
  } catch (e) {
    showError(e);
  }
}

function linkedImage(job, name) {
  const img = el("img", { alt: name });
  api.artifactLink(job, name).then((url) => { img.src = url; }).catch(showError);
  return img;
}

async function results(root, job) {
  const names = (job.artifacts || []).map((a) => a.name);
  if (job.state === "FAILED") {
    root.append(el("p", { id: "kept", class: "kept" }, `Kept before it failed: ${names.length} files.`));
  }
  root.append(el("h3", {}, "Downloads"), el("ul", { id: "downloads" }, (job.artifacts || []).map((a) =>
    el("li", {}, el("a", { href: "#", "data-name": a.name, onclick: (e) => download(e, job.name, a.name) }, a.name),
      ` ${Number(a.digest.size_bytes).toLocaleString()} bytes, ${a.media_type}`))));
  if (!names.includes("report.json")) return;
  const report = await (await api.fetchArtifact(job.name, "report.json")).json();
  root.append(el("h3", {}, "Fidelity"), numbers(report));
  const floor = (report.similarity || {}).floor_warning;
  if (floor) root.append(el("p", { id: "floor-warning", class: "warning" }, `Warning: ${floor.text}`));
  const previews = names.filter((n) => n.endsWith(".png"));
  if (previews.length) {
    root.append(el("h3", {}, "Previews"), el("div", { class: "previews" }, previews.map((n) =>
      el("figure", {}, linkedImage(job.name, n), el("figcaption", {}, n)))));
  }
  root.append(el("h3", {}, "Pieces"), piecesTable(report), el("h3", {}, "Sheets and bodies"),
    representationTable(report), el("h3", {}, "Volume mesh"), qualityTable(report));
  if (report.flow) {
    const canvas = el("canvas", { id: "permeability_chart", width: 560, height: 280 });
    root.append(el("h3", {}, "Permeability"), permeabilityTable(report.flow), canvas);
    permeabilityChart(canvas, report.flow);
  }
  const ply = names.find((n) => n.endsWith(".ply"));
  if (!ply) return;
  const bytes = await (await api.fetchArtifact(job.name, ply)).arrayBuffer();
  // The aperture a flow model takes, in the volume's unit; a PLY without it: the thickness.
  const unit = unitOf(report);
  const physical = unit !== "voxels";
  let field = physical ? "aperture" : "aperture_voxels";
  let values = faceValues(bytes, field);
  if (!values.length) {
    field = physical ? "thickness" : "thickness_voxels";
    values = faceValues(bytes, field);
  }
  const what = field.startsWith("aperture") ? "aperture" : "thickness";
  const canvas = el("canvas", { id: "histogram", width: 560, height: 240 });
  root.append(el("h3", {}, what[0].toUpperCase() + what.slice(1)), canvas);
  thicknessHistogram(canvas, values, `${what} per triangle (${unit})`);
  const view = el("div", { id: "view3d", class: "view3d" });
  const boundary = el("input", { id: "boundary", type: "checkbox", disabled: !report.volume_mesh });
  root.append(el("h3", {}, "Surface"), el("label", {}, boundary, " volume mesh boundary"), view);
  const { showSurface } = await import("./viewer.js");
  const viewer = showSurface(view, bytes, report.input);
  root.append(colourLegend(viewer.range, unit));
  boundary.addEventListener("change", () => viewer.setBoundary(boundary.checked));
  view.dataset.ready = "1";
  return viewer;
}

export function jobPage(app, name) {
  const abort = new AbortController();
  const head = el("div", { id: "job_head" });
  const body = el("div", { id: "job_results" });
  app.replaceChildren(el("section", {}, el("h2", {}, name), head, body));
  let viewer = null;
  const render = (j) => {
    head.replaceChildren(progressBar(jobFraction(j), jobLabel(j), j.state),
      el("p", { id: "job_state", "data-state": j.state }, j.state,
        !isTerminal(j.state) ? el("button", { onclick: () => api.cancelJob(name).catch(showError) }, "Cancel") : ""),
      j.error && j.error.message ? el("p", { class: "error", id: "job_error" }, j.error.message) : "");
  };
  (async () => {
    try {
      let last = await api.getJob(name);
      render(last);
      if (!isTerminal(last.state)) {
        await api.watchJob(name, (j) => { last = j; render(j); }, abort.signal);
        last = await api.getJob(name);
        render(last);
      }
      // A failed job shows what its run kept (the surface when the volume stage failed).
      if ((last.artifacts || []).length) viewer = await results(body, last);
    } catch (e) {
      if (!abort.signal.aborted) showError(e);
    }
  })();
  return () => {
    abort.abort();
    if (viewer) viewer.dispose();
  };
}
