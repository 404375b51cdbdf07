// The gateway's HTTP/JSON API, with the bearer token from the token field.

export function token() {
  return localStorage.getItem("sheetmesh.token") || "";
}

export function setToken(t) {
  localStorage.setItem("sheetmesh.token", t);
}

function headers(extra = {}) {
  const h = { ...extra };
  if (token()) h.Authorization = "Bearer " + token();
  return h;
}

// An error from the gateway: its message names the field and value.
export class ApiError extends Error {
  constructor(status, body) {
    super(body && body.message ? body.message : `HTTP ${status}`);
    this.status = status;
    this.code = body && body.status;
  }
}

async function check(resp) {
  if (resp.ok) return resp;
  let body = null;
  try {
    body = await resp.json();
  } catch (e) {
    body = { message: `HTTP ${resp.status} ${resp.statusText}` };
  }
  throw new ApiError(resp.status, body);
}

export async function call(method, path, body) {
  const init = { method, headers: headers(body ? { "Content-Type": "application/json" } : {}) };
  if (body) init.body = JSON.stringify(body);
  const resp = await check(await fetch(path, init));
  return resp.status === 204 ? null : resp.json();
}

export const listJobs = (pageSize = 50) => call("GET", `/v1/jobs?page_size=${pageSize}`);
export const getJob = (name) => call("GET", `/v1/${name}`);
export const createJob = (req) => call("POST", "/v1/jobs", req);
export const cancelJob = (name) => call("POST", `/v1/${name}:cancel`, {});

// A link to one artifact the browser can open without headers (an image, a download): the
// gateway seals the token into it for a few minutes, so the token never shows in a URL.
export async function artifactLink(job, name) {
  const r = await call("POST", `/v1/${job}/artifacts/${encodeURIComponent(name)}:link`, {});
  return r.url;
}

export async function fetchArtifact(job, name) {
  const resp = await check(await fetch(`/v1/${job}/artifacts/${encodeURIComponent(name)}`, { headers: headers() }));
  return resp;
}

// Calls onJob(job) at every change until the job finishes (newline-delimited JSON read
// as it comes, so that the token travels in a header).
export async function watchJob(name, onJob, signal) {
  const resp = await check(await fetch(`/v1/${name}:watch`, { headers: headers({ Accept: "application/x-ndjson" }), signal }));
  const reader = resp.body.getReader();
  const text = new TextDecoder();
  let buf = "";
  for (;;) {
    const { value, done } = await reader.read();
    if (done) break;
    buf += text.decode(value, { stream: true });
    let nl;
    while ((nl = buf.indexOf("\n")) >= 0) {
      const line = buf.slice(0, nl).trim();
      buf = buf.slice(nl + 1);
      if (!line) continue;
      const msg = JSON.parse(line);
      if (msg.error) throw new ApiError(500, msg.error);
      if (msg.result && msg.result.job) onJob(msg.result.job, msg.result.heartbeat);
    }
  }
}

export { headers, check };
