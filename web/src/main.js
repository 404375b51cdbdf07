// The sheetmesh front-end: upload a volume, set the parameters, follow the jobs, and read
// a job's results (numbers, tables, histogram, 3D view, downloads).
import "./style.css";
import * as api from "./api.js";
import { uploadFile } from "./upload.js";
import { jobPage } from "./job_page.js";
import { el, isTerminal, jobFraction, jobLabel, progressBar, showError } from "./dom.js";
// The parameter table's defaults (`sheetmesh-pipeline params --json`, written by
// tools/readme_parameters.sh): the form starts where every other interface starts.
import defaults from "./parameter_defaults.json";

const app = document.getElementById("app");
// --- the jobs page -----------------------------------------------------------------------

let listTimer = null;
let chosenFile = null;

function parametersForm() {
  return el("fieldset", { class: "params" }, el("legend", {}, "Parameters"),
    el("label", {}, "Budget ", el("select", { id: "budget" },
      el("option", { value: "r" }, "r (element size, voxels)"),
      el("option", { value: "triangles" }, "triangles"))),
    el("input", { id: "budget_value", type: "number", step: "any", min: "0", value: String(defaults.r) }),
    el("label", {}, "Sheet labels ",
      el("input", { id: "labels", value: "", size: 12, placeholder: "every non-zero voxel" })),
    el("label", { title: "a scan as it came: sheets found by their sheetness, apertures from the grey levels" },
      el("input", { id: "grey", type: "checkbox" }), " grey scan"),
    el("label", {}, el("input", { id: "extract", type: "checkbox", checked: defaults.extract }), " extraction"),
    el("label", {}, el("input", { id: "volume_mesh", type: "checkbox", checked: defaults.volume_mesh }),
      " volume mesh"),
    el("label", { title: "a volume too big for one process: cut into bricks of this size (auto, 512, 512x512x256) that the server's workers read at once; the result is the same" },
      "Bricks ", el("input", { id: "bricks", value: "", size: 10, placeholder: "one process" })),
    el("label", {}, el("input", { id: "no_cache", type: "checkbox" }), " run again (no cache)"));
}

function readParameters() {
  const p = {};
  const kind = document.getElementById("budget").value;
  const v = document.getElementById("budget_value").value.trim();
  if (v !== "") p[kind] = kind === "triangles" ? String(Math.round(Number(v))) : Number(v);
  const labels = document.getElementById("labels").value.split(/[ ,]+/).filter((s) => s !== "");
  // A grey scan is its own sheet phase: labels go with segmented volumes only.
  if (document.getElementById("grey").checked) p.grey = true;
  else if (labels.length) p.labels = labels.map(Number);
  p.extract = document.getElementById("extract").checked;
  p.volume_mesh = document.getElementById("volume_mesh").checked;
  return p;
}

async function startJob() {
  showError(null);
  const status = document.getElementById("upload_status");
  const bar = document.getElementById("upload_bar");
  try {
    if (!chosenFile) throw new Error("drop a volume (or choose one) first");
    const digest = await uploadFile(chosenFile, (phase, f) => {
      bar.replaceWith(Object.assign(progressBar(f, `${phase} ${Math.round(100 * f)}%`), { id: "upload_bar" }));
    });
    status.textContent = digest.resumed_from > 0 ?
      `uploaded (resumed at ${digest.resumed_from} bytes)` : "uploaded";
    sessionStorage.setItem("sheetmesh.last_upload", JSON.stringify({ file: chosenFile.name, ...digest }));
    const job = await api.createJob({
      request_id: crypto.randomUUID ? crypto.randomUUID() : String(Date.now()) + Math.random(),
      input: { volume_digest: { hash: digest.hash, size_bytes: digest.size_bytes }, file_name: chosenFile.name },
      parameters: readParameters(),
      no_cache: document.getElementById("no_cache").checked,
      bricks: document.getElementById("bricks").value.trim(),
    });
    location.hash = `#/${job.name}`;
  } catch (e) {
    showError(e);
  }
}

async function refreshList() {
  const table = document.getElementById("jobs");
  if (!table) return;
  try {
    const resp = await api.listJobs();
    const rows = (resp.jobs || []).map((j) => el("tr", { "data-job": j.name },
      el("td", {}, el("a", { href: `#/${j.name}` }, j.name.replace("jobs/", ""))),
      el("td", {}, (j.input && j.input.file_name) || (j.input && j.input.volume_path) || ""),
      el("td", {}, progressBar(jobFraction(j), jobLabel(j), j.state)),
      el("td", {}, j.create_time ? new Date(j.create_time).toLocaleString() : "")));
    table.tBodies[0].replaceChildren(...rows);
    const live = (resp.jobs || []).some((j) => !isTerminal(j.state));
    listTimer = setTimeout(refreshList, live ? 1000 : 5000);
  } catch (e) {
    showError(e);
    listTimer = setTimeout(refreshList, 5000);
  }
}

function jobsPage() {
  const drop = el("div", { id: "drop", class: "drop", tabindex: 0 },
    el("p", {}, "Drop a volume here (raw with its size in the name, e.g. rock_256x256x200_u8.raw; TIFF; NRRD; VDB), or "),
    el("input", { id: "file", type: "file", onchange: (ev) => choose(ev.target.files[0]) }));
  const choose = (f) => {
    chosenFile = f || null;
    document.getElementById("chosen").textContent = f ? `${f.name} (${f.size.toLocaleString()} bytes)` : "";
  };
  drop.addEventListener("dragover", (ev) => { ev.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  drop.addEventListener("drop", (ev) => {
    ev.preventDefault();
    drop.classList.remove("over");
    choose(ev.dataTransfer.files[0]);
  });
  app.replaceChildren(
    el("section", {}, el("h2", {}, "New job"), drop, el("p", { id: "chosen" }),
      parametersForm(),
      el("div", { class: "row" }, el("button", { id: "start", onclick: startJob }, "Upload and start"),
        Object.assign(progressBar(0, ""), { id: "upload_bar" }), el("span", { id: "upload_status" }))),
    el("section", {}, el("h2", {}, "Jobs"),
      el("table", { id: "jobs" }, el("thead", {}, el("tr", {}, el("th", {}, "job"), el("th", {}, "volume"),
        el("th", {}, "state"), el("th", {}, "created"))), el("tbody"))));
  choose(chosenFile);
  refreshList();
}

// --- routing -----------------------------------------------------------------------------

let leave = null;

function route() {
  clearTimeout(listTimer);
  if (leave) leave();
  leave = null;
  showError(null);
  const m = location.hash.match(/^#\/(jobs\/[A-Za-z0-9_-]+)$/);
  if (m) leave = jobPage(app, m[1]);
  else jobsPage();
}

const tokenInput = document.getElementById("token");
tokenInput.value = api.token();
// A new token applies at once; the page keeps what was typed into it.
tokenInput.addEventListener("input", () => api.setToken(tokenInput.value.trim()));
tokenInput.addEventListener("change", () => {
  api.setToken(tokenInput.value.trim());
  showError(null);
  if (document.getElementById("jobs")) {
    clearTimeout(listTimer);
    refreshList();
  } else {
    route();
  }
});
window.addEventListener("hashchange", route);
route();
