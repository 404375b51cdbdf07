// Resumable upload of a File: SHA-256 computed in the browser as the file is read, then
// chunks PUT at their offsets; after a break (or a reload) the upload's status says where
// to go on. The server checks the digest when the last chunk arrives.
import { createSHA256 } from "hash-wasm";
import { check, headers } from "./api.js";

const CHUNK = 8 << 20;

function uuid() {
  return crypto.randomUUID ? crypto.randomUUID().replace(/-/g, "") :
    Array.from(crypto.getRandomValues(new Uint8Array(16)), (b) => b.toString(16).padStart(2, "0")).join("");
}

export async function digestOf(file, onProgress) {
  const h = await createSHA256();
  h.init();
  for (let at = 0; at < file.size; at += CHUNK) {
    const part = new Uint8Array(await file.slice(at, at + CHUNK).arrayBuffer());
    h.update(part);
    onProgress(Math.min(file.size, at + CHUNK) / Math.max(1, file.size));
  }
  return h.digest("hex");
}

// Uploads `file`; onProgress(phase, fraction). Returns the digest {hash, size_bytes}.
// `stopAfter` (bytes) ends the upload early, as a broken connection would (for tests).
export async function uploadFile(file, onProgress, { stopAfter = Infinity } = {}) {
  const hash = await digestOf(file, (f) => onProgress("hashing", f));
  const size = file.size;
  const key = `sheetmesh.upload.${hash}.${size}`;
  let id = localStorage.getItem(key);
  if (!id) {
    id = uuid();
    localStorage.setItem(key, id);
  }
  const base = `/v1/uploads/${id}/blobs/${hash}/${size}`;
  let offset = 0;
  const status = await fetch(`${base}:status`, { headers: headers() });
  if (status.ok) {
    const s = await status.json();
    if (s.complete) {
      onProgress("uploaded", 1);
      localStorage.removeItem(key);
      return { hash, size_bytes: String(size), resumed_from: size };
    }
    offset = Number(s.committed_size || 0);
  }
  const resumedFrom = offset;
  do {
    const end = Math.min(size, offset + CHUNK, stopAfter);
    const last = end === size;
    const resp = await check(await fetch(`${base}?offset=${offset}${last ? "&finish=true" : ""}`, {
      method: "PUT",
      headers: headers({ "Content-Type": "application/octet-stream" }),
      body: file.slice(offset, end),
    }));
    const r = await resp.json();
    offset = Number(r.committed_size);
    onProgress("uploading", size ? offset / size : 1);
    if (r.complete) break;
    if (end >= stopAfter) throw new Error(`upload stopped at ${offset} of ${size} bytes`);
  } while (offset < size);
  localStorage.removeItem(key);
  onProgress("uploaded", 1);
  return { hash, size_bytes: String(size), resumed_from: resumedFrom };
}
