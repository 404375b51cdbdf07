// The surface in 3D: sheet triangles coloured by the thickness they carry, bodies (pieces
// meshed as closed surfaces) grey, turned and zoomed with the mouse; the volume mesh's
// boundary (the box) as an optional wireframe.
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { PLYLoader } from "three/examples/jsm/loaders/PLYLoader.js";

// Blue (thin) to red (thick).
function colourOf(t) {
  const c = new THREE.Color();
  c.setHSL((1 - Math.min(1, Math.max(0, t))) * 0.66, 0.85, 0.5);
  return c;
}

// `input` is the report's input (dims, spacing, origin): the PLY's coordinates are physical,
// voxel (i, j, k) at origin + spacing · (i, j, k).
export function showSurface(container, plyBytes, input) {
  const loader = new PLYLoader();
  loader.setCustomPropertyNameMapping({ thickness: ["thickness"], body: ["body"] });
  const geometry = loader.parse(plyBytes);
  const thick = geometry.getAttribute("thickness");
  const body = geometry.getAttribute("body");
  const n = geometry.getAttribute("position").count;
  const isBody = (i) => body && body.getX(i) > 0;
  let lo = Infinity, hi = -Infinity;
  for (let i = 0; thick && i < n; ++i) {
    if (isBody(i)) continue;
    lo = Math.min(lo, thick.getX(i));
    hi = Math.max(hi, thick.getX(i));
  }
  const colours = new Float32Array(3 * n);
  const grey = new THREE.Color(0x9aa0a6);
  for (let i = 0; i < n; ++i) {
    const t = thick && hi > lo ? (thick.getX(i) - lo) / (hi - lo) : 0.5;
    const c = isBody(i) ? grey : colourOf(t);
    colours.set([c.r, c.g, c.b], 3 * i);
  }
  geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  geometry.computeVertexNormals();

  const width = container.clientWidth || 640, height = container.clientHeight || 480;
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  container.replaceChildren(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f5f7);
  const mesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide }));
  scene.add(mesh);
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  const sun = new THREE.DirectionalLight(0xffffff, 0.9);
  sun.position.set(1, 2, 3);
  scene.add(sun);

  const dims = (input && input.dims) || [1, 1, 1];
  const spacing = (input && input.spacing) || [1, 1, 1];
  const origin = (input && input.origin) || [0, 0, 0];
  // The box the voxels fill, in the mesh's units.
  const lo3 = [0, 1, 2].map((k) => origin[k] - 0.5 * spacing[k]);
  const size = [0, 1, 2].map((k) => dims[k] * spacing[k]);
  const box = new THREE.LineSegments(
    new THREE.EdgesGeometry(new THREE.BoxGeometry(size[0], size[1], size[2])),
    new THREE.LineBasicMaterial({ color: 0x555555 }));
  box.position.set(lo3[0] + size[0] / 2, lo3[1] + size[1] / 2, lo3[2] + size[2] / 2);
  box.visible = false;
  scene.add(box);

  const centre = box.position.clone();
  const span = Math.max(...size);
  const camera = new THREE.PerspectiveCamera(40, width / height, span / 100, span * 20);
  camera.position.set(centre.x + span * 1.2, centre.y - span * 1.4, centre.z + span * 1.1);
  camera.up.set(0, 0, 1);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();
  const draw = () => renderer.render(scene, camera);
  controls.addEventListener("change", draw);
  draw();
  return {
    // The thickness the colours run over (the PLY's, in the mesh's unit), and whether
    // there are bodies (grey).
    range: { lo, hi, bodies: n > 0 && Array.from({ length: n }, (_, i) => isBody(i)).some(Boolean) },
    setBoundary(on) {
      box.visible = on;
      draw();
    },
    dispose() {
      controls.dispose();
      renderer.dispose();
      geometry.dispose();
    },
  };
}
