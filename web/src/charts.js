// The aperture (or thickness) histogram of the surface's triangles, and the permeability's
// bars.
import { BarController, BarElement, CategoryScale, Chart, Legend, LinearScale, LogarithmicScale, Tooltip } from "chart.js";

Chart.register(BarController, BarElement, CategoryScale, Legend, LinearScale, LogarithmicScale, Tooltip);

// `axis` names what is counted, with its unit ("aperture (mm)").
export function thicknessHistogram(canvas, values, axis = "thickness (voxels)", bins = 20) {
  if (!values.length) return null;
  let lo = Math.min(...values), hi = Math.max(...values);
  if (hi <= lo) hi = lo + 1;
  const counts = new Array(bins).fill(0);
  for (const v of values) counts[Math.min(bins - 1, Math.floor(((v - lo) / (hi - lo)) * bins))]++;
  const labels = counts.map((_, i) => Number((lo + ((i + 0.5) * (hi - lo)) / bins).toPrecision(3)).toString());
  canvas.dataset.counts = JSON.stringify(counts);  // what is drawn, for tests and scripts
  canvas.dataset.axis = axis;
  return new Chart(canvas, {
    type: "bar",
    data: { labels, datasets: [{ label: "triangles", data: counts, backgroundColor: "#4a7bd0" }] },
    options: {
      animation: false,
      responsive: false,
      plugins: { tooltip: { enabled: true } },
      scales: {
        x: { title: { display: true, text: axis } },
        y: { title: { display: true, text: "triangles" }, beginAtZero: true },
      },
    },
  });
}

// The permeability in darcy on a log scale: per axis the tensor's diagonal, the permeameter
// and the image's permeameter (where the report has it), then the tensor's principal values.
// `flow` is report.json's flow section.
export function permeabilityChart(canvas, flow) {
  const diag = (t) => [0, 1, 2].map((d) => t[d][d]);
  const labels = ["x", "y", "z", "k1", "k2", "k3"];
  const none = [null, null, null];
  const datasets = [
    { label: "tensor (pressure linear on the box)", data: [...diag(flow.permeability_darcy), ...flow.principal_darcy], backgroundColor: "#4a7bd0" },
    { label: "permeameter (sides closed)", data: [...flow.permeameter_darcy, ...none], backgroundColor: "#ffaa28" },
  ];
  const image = flow.image_reference;
  if (image && image.permeability_m2) {
    const darcy = diag(image.permeability_m2).map((k) => k / 9.869233e-13);
    datasets.push({ label: "the image's permeameter (voxel grid)", data: [...darcy, ...none], backgroundColor: "#6ec878" });
  }
  canvas.dataset.values = JSON.stringify(datasets.map((d) => d.data));  // what is drawn
  return new Chart(canvas, {
    type: "bar",
    data: { labels, datasets },
    options: {
      animation: false,
      responsive: false,
      plugins: { legend: { display: true, position: "bottom" }, tooltip: { enabled: true } },
      scales: {
        x: { title: { display: true, text: "along x, y, z; k1–k3 the principal values" } },
        y: {
          type: "logarithmic",
          title: { display: true, text: "permeability (darcy)" },
          ticks: { callback: (v) => Number(v).toExponential(1) },
        },
      },
    },
  });
}

// A per-face property (`name`, e.g. "aperture" or "thickness_voxels") of a binary
// little-endian or ASCII PLY written by sheetmesh; [] where the PLY has none.
export function faceValues(bytes, name) {
  const head = new TextDecoder().decode(bytes.slice(0, Math.min(bytes.byteLength, 4096)));
  const end = head.indexOf("end_header");
  if (end < 0) return [];
  const header = head.slice(0, end).split("\n").map((l) => l.trim());
  const elements = [];
  for (const l of header) {
    const w = l.split(/\s+/);
    if (w[0] === "element") elements.push({ name: w[1], count: Number(w[2]), props: [] });
    else if (w[0] === "property" && elements.length) elements[elements.length - 1].props.push(w);
  }
  const binary = header.some((l) => l.startsWith("format binary_little_endian"));
  const size = { char: 1, uchar: 1, short: 2, ushort: 2, int: 4, uint: 4, float: 4, double: 8, int8: 1, uint8: 1, int32: 4, uint32: 4, float32: 4, float64: 8 };
  const out = [];
  if (!binary) {
    // ASCII: one element per line after the header, its properties in order.
    const text = new TextDecoder().decode(bytes);
    const lines = text.slice(text.indexOf("\n", text.indexOf("end_header")) + 1).split("\n");
    let line = 0;
    for (const e of elements) {
      for (let i = 0; i < e.count && line < lines.length; ++i, ++line) {
        if (e.name !== "face") continue;
        const w = lines[line].trim().split(/\s+/).map(Number);
        let k = 0;
        for (const p of e.props) {
          if (p[1] === "list") k += 1 + w[k];
          else if (p[2] === name) out.push(w[k++]);
          else k++;
        }
      }
    }
    return out;
  }
  const view = new DataView(bytes);
  let at = head.indexOf("\n", end) + 1;
  const read = (type) => {
    let v;
    switch (type) {
      case "float": case "float32": v = view.getFloat32(at, true); break;
      case "double": case "float64": v = view.getFloat64(at, true); break;
      case "int": case "int32": v = view.getInt32(at, true); break;
      case "uint": case "uint32": v = view.getUint32(at, true); break;
      case "uchar": case "uint8": v = view.getUint8(at); break;
      case "char": case "int8": v = view.getInt8(at); break;
      case "short": v = view.getInt16(at, true); break;
      default: v = view.getUint16(at, true);
    }
    at += size[type];
    return v;
  };
  for (const e of elements) {
    for (let i = 0; i < e.count; ++i) {
      for (const p of e.props) {
        if (p[1] === "list") {
          const k = read(p[2]);
          for (let j = 0; j < k; ++j) read(p[3]);
        } else {
          const v = read(p[1]);
          if (e.name === "face" && p[2] === name) out.push(v);
        }
      }
    }
  }
  return out;
}
