// Small DOM helpers shared by the pages.

const errorBox = document.getElementById("error");

export function showError(e) {
  errorBox.textContent = e ? (e.message || String(e)) : "";
  errorBox.hidden = !e;
}

export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null && v !== false) e.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children.flat()) e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  return e;
}

// SUCCEEDED, FAILED or CANCELLED: the job has ended (the one test of it in the front-end).
export function isTerminal(state) {
  return state === "SUCCEEDED" || state === "FAILED" || state === "CANCELLED";
}

// `state` (a job's) colours the bar: red when FAILED, grey when CANCELLED.
export function progressBar(fraction, label, state = "") {
  const bar = el("div", { class: `bar ${state.toLowerCase()}`.trim(), role: "progressbar", "aria-valuemin": 0,
    "aria-valuemax": 100, "aria-valuenow": Math.round(100 * fraction), "data-state": state || undefined });
  bar.append(el("div", { class: "fill", style: `width:${(100 * fraction).toFixed(1)}%` }), el("span", {}, label));
  return bar;
}

export function jobFraction(j) {
  if (j.state === "SUCCEEDED") return 1;
  const p = j.progress || {};
  // A job run as bricks, while they run: the share of their work done.
  if (p.stage === "bricks") return Math.min(1, p.fraction || 0);
  if (!p.stage_count) return 0;
  return Math.min(1, ((p.stage_index || 1) - 1 + (p.fraction || 0)) / p.stage_count);
}

export function jobLabel(j) {
  const p = j.progress || {};
  if (j.state === "RUNNING" && p.stage === "bricks") return `RUNNING ${p.message || "bricks"}`;
  if (j.state === "RUNNING") return `RUNNING ${p.stage || ""} ${Math.round(100 * jobFraction(j))}%`;
  return j.state;
}


