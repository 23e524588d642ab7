// The mesh viewer of results/viewer/index.html: one model at a time, our mesh on the left and a
// baseline at a matched triangle count on the right, both seen through one camera so that they turn
// and zoom together. The data come from scripts/make_viewer.py as classic scripts (see its docstring
// for why); window.cdpViewer is what viewer/test/browser.mjs drives.
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { vertexColors, legendLabels, tableOf, colorAt } from "./colormaps.js";

const manifest = window.CDP_VIEWER_MANIFEST;
const errors = [];
window.addEventListener("error", (e) => errors.push(String(e.message || e)));
window.addEventListener("unhandledrejection", (e) => errors.push(String(e.reason)));

const $ = (id) => document.getElementById(id);
const panes = [...document.querySelectorAll(".pane")];
const BACKGROUND = 0xffffff;
const SURFACE = 0xd9d4cc;

const canvas = $("view");
// preserveDrawingBuffer: the test reads the pixels back to check that each pane shows its mesh.
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.setClearColor(BACKGROUND);
const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
const controls = new OrbitControls(camera, canvas);
controls.addEventListener("change", render);

// One scene per pane, each lit from near the camera so no side of a model it faces is left dark.
const scenes = [0, 1].map(() => {
  const scene = new THREE.Scene();
  scene.add(new THREE.HemisphereLight(0xffffff, 0x505050, 0.7));
  const light = new THREE.DirectionalLight(0xffffff, 2.2);
  scene.add(light, light.target);
  scene.userData.light = light;
  return scene;
});
const shown = [null, null]; // {group, geometry, run} per pane

const state = { model: null, baseline: null, shading: "phong", wireframe: false, color: "none" };
const geometries = new Map(); // data key -> Promise<BufferGeometry>
const loaded = {}; // data key -> {vertices, triangles}

function decode(b64, Type) {
  const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  return new Type(bytes.buffer);
}

function loadScript(src) {
  return new Promise((resolve, reject) => {
    const s = document.createElement("script");
    s.src = src;
    s.onload = resolve;
    s.onerror = () => reject(new Error("could not load " + src));
    document.head.appendChild(s);
  });
}

function geometryOf(run) {
  if (!geometries.has(run.key)) {
    geometries.set(run.key, loadScript(run.file).then(() => {
      const d = (window.CDP_VIEWER_MESHES || {})[run.key];
      if (!d) throw new Error(run.file + " did not define the mesh " + run.key);
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(decode(d.position, Float32Array), 3));
      const Index = d.index_type === "uint16" ? Uint16Array : Uint32Array;
      g.setIndex(new THREE.BufferAttribute(decode(d.index, Index), 1));
      if (d.hasNormals) g.setAttribute("normal", new THREE.BufferAttribute(decode(d.normal, Int8Array), 3, true));
      else g.computeVertexNormals();
      g.userData.k1 = decode(d.k1, Float32Array);
      g.userData.k2 = decode(d.k2, Float32Array);
      g.computeBoundingSphere();
      const vertices = g.getAttribute("position").count, triangles = g.getIndex().count / 3;
      if (vertices !== d.vertices || triangles !== d.triangles)
        throw new Error(run.key + ": decoded " + vertices + " vertices and " + triangles + " triangles, the data say " +
          d.vertices + " and " + d.triangles);
      loaded[run.key] = { vertices, triangles };
      delete window.CDP_VIEWER_MESHES[run.key]; // the base64 text is no longer needed
      return g;
    }));
  }
  return geometries.get(run.key);
}

function modelOf(id) {
  return manifest.models.find((m) => m.id === id) || manifest.models[0];
}

function baselinesOf(model) {
  return model.runs.filter((r) => r.method !== "adaptive");
}

// The colour maps are sRGB; three.js takes vertex colours as linear.
const scratch = new THREE.Color();
const toLinear = (c) => scratch.setRGB(c, c, c, THREE.SRGBColorSpace).r;

function makeGroup(geometry, model) {
  const colored = state.color !== "none" && model.colors;
  if (colored) {
    const colors = vertexColors(state.color, model.colors[state.color], geometry.userData.k1, geometry.userData.k2,
      toLinear);
    geometry.setAttribute("color", new THREE.BufferAttribute(colors, 3));
  }
  const material = new THREE.MeshPhongMaterial({
    color: colored ? 0xffffff : SURFACE, vertexColors: !!colored, flatShading: state.shading === "flat",
    shininess: 40, specular: 0x222222, side: THREE.DoubleSide,
    // Pushes the surface back a little so that the wireframe drawn on it is not half hidden.
    polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
  });
  const group = new THREE.Group();
  group.add(new THREE.Mesh(geometry, material));
  if (state.wireframe) {
    if (!geometry.userData.wire) geometry.userData.wire = new THREE.WireframeGeometry(geometry);
    group.add(new THREE.LineSegments(geometry.userData.wire,
      new THREE.LineBasicMaterial({ color: 0x202020, transparent: true, opacity: 0.45 })));
  }
  return group;
}

function showInPane(i, run, geometry, model) {
  const scene = scenes[i];
  if (shown[i]) {
    scene.remove(shown[i].group);
    shown[i].group.traverse((o) => o.material && o.material.dispose());
  }
  const group = makeGroup(geometry, model);
  scene.add(group);
  shown[i] = { group, geometry, run };
  const pane = panes[i];
  pane.querySelector("h2").textContent = run.label;
  document.querySelectorAll("#figures > div")[i].innerHTML = run.figures
    .map(([k, v]) => k === "topology" ? '<span class="wide">topology: ' + escapeHtml(v) + "</span>"
      : "<span>" + escapeHtml(k) + '</span><span class="v">' + escapeHtml(v) + "</span>").join("");
}

function escapeHtml(s) {
  return String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" }[c]));
}

function frame(geometry) {
  const s = geometry.boundingSphere;
  // Fits the bounding sphere in the narrower of the pane's two angles of view.
  const half = Math.atan(Math.tan(THREE.MathUtils.degToRad(camera.fov / 2)) * Math.min(1, camera.aspect));
  const d = s.radius / Math.sin(half);
  controls.target.copy(s.center);
  camera.position.copy(s.center).add(new THREE.Vector3(0.35, 0.3, 1).normalize().multiplyScalar(d));
  camera.near = d / 100;
  camera.far = d * 10;
  camera.updateProjectionMatrix();
  controls.update();
}

function setStatus(i, text, isError) {
  const el = panes[i].querySelector(".status");
  el.textContent = text;
  el.classList.toggle("error", !!isError);
}

// Shows a model with one of its baselines; resolves once both meshes are drawn.
let generation = 0;
async function show(modelId, baselineMethod, { reframe = true } = {}) {
  const model = modelOf(modelId);
  const baselines = baselinesOf(model);
  const baseline = baselines.find((r) => r.method === baselineMethod) || baselines[0];
  const ours = model.runs.find((r) => r.method === "adaptive");
  const changedModel = state.model !== model.id;
  state.model = model.id;
  state.baseline = baseline ? baseline.method : null;
  syncControls();
  const mine = ++generation;
  const runs = [ours, baseline];
  runs.forEach((r, i) => r && setStatus(i, "loading " + r.file + " …"));
  const geoms = await Promise.all(runs.map((r, i) => r ? geometryOf(r).catch((e) => {
    setStatus(i, e.message, true);
    throw e;
  }) : null));
  if (mine !== generation) return; // a later choice overtook this one
  runs.forEach((r, i) => {
    if (r) {
      showInPane(i, r, geoms[i], model);
      setStatus(i, "");
    }
  });
  if (reframe && changedModel) frame(geoms[0]);
  updateLegend(model);
  render();
}

function restyle() {
  const model = modelOf(state.model);
  shown.forEach((s, i) => s && showInPane(i, s.run, s.geometry, model));
  updateLegend(model);
  syncControls();
  render();
}

function updateLegend(model) {
  const legend = $("legend");
  legend.hidden = state.color === "none" || !model.colors;
  if (legend.hidden) return;
  const range = model.colors[state.color];
  const c = legend.querySelector("canvas");
  const ctx = c.getContext("2d");
  const rgb = [0, 0, 0];
  for (let x = 0; x < c.width; x++) {
    colorAt(tableOf(state.color), x / (c.width - 1), rgb, 0);
    ctx.fillStyle = "rgb(" + rgb.map((v) => Math.round(255 * v)).join(",") + ")";
    ctx.fillRect(x, 0, 1, c.height);
  }
  const spans = legend.querySelectorAll(".ends span");
  legendLabels(state.color, range).forEach((t, i) => (spans[i].textContent = t));
}

function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (!w || !h) return;
  renderer.setSize(w, h, false);
  camera.aspect = w / 2 / h;
  camera.updateProjectionMatrix();
  render();
}

// The key light sits above and left of the camera, and moves with it: a light straight from the eye
// would flatten the shapes it faces.
const lightOffset = new THREE.Vector3();
function keyLight() {
  const d = camera.position.distanceTo(controls.target);
  camera.updateMatrixWorld();
  return camera.localToWorld(lightOffset.set(-0.5 * d, 0.7 * d, 0));
}

function render() {
  const size = renderer.getSize(new THREE.Vector2());
  const half = Math.floor(size.x / 2);
  renderer.setScissorTest(true);
  scenes.forEach((scene, i) => {
    scene.userData.light.position.copy(keyLight());
    scene.userData.light.target.position.copy(controls.target);
    renderer.setViewport(i * half, 0, half, size.y);
    renderer.setScissor(i * half, 0, half, size.y);
    renderer.render(scene, camera);
  });
  writeHash();
}

// The state lives in the address (#model=torus&vs=mc&shading=flat&wire=1&color=mac) so a view can be shared.
function readHash() {
  const p = new URLSearchParams(location.hash.slice(1));
  if (p.get("shading")) state.shading = p.get("shading") === "flat" ? "flat" : "phong";
  if (p.get("wire")) state.wireframe = p.get("wire") === "1";
  if (p.get("color") && ["none", "shape_index", "mean", "mac"].includes(p.get("color"))) state.color = p.get("color");
  return { model: p.get("model"), vs: p.get("vs") };
}

function writeHash() {
  if (!state.model) return;
  const h = "#" + new URLSearchParams({ model: state.model, vs: state.baseline || "", shading: state.shading,
    wire: state.wireframe ? "1" : "0", color: state.color }).toString();
  if (location.hash !== h) history.replaceState(null, "", h);
}

function syncControls() {
  $("model").value = state.model;
  const sel = $("baseline");
  const model = modelOf(state.model);
  sel.innerHTML = baselinesOf(model)
    .map((r) => '<option value="' + r.method + '">' + escapeHtml(r.label) + "</option>").join("");
  sel.value = state.baseline;
  $("shading").value = state.shading;
  $("wireframe").checked = state.wireframe;
  $("color").value = state.color;
  $("color").disabled = !model.colors;
}

function start() {
  $("model").innerHTML = manifest.models
    .map((m) => '<option value="' + m.id + '">' + escapeHtml(m.title) + "</option>").join("");
  $("model").addEventListener("change", (e) => show(e.target.value, state.baseline));
  $("baseline").addEventListener("change", (e) => show(state.model, e.target.value));
  $("shading").addEventListener("change", (e) => { state.shading = e.target.value; restyle(); });
  $("wireframe").addEventListener("change", (e) => { state.wireframe = e.target.checked; restyle(); });
  $("color").addEventListener("change", (e) => { state.color = e.target.value; restyle(); });
  $("reset").addEventListener("click", () => shown[0] && (frame(shown[0].geometry), render()));
  new ResizeObserver(resize).observe(canvas);
  resize();
  const want = readHash();
  return show(want.model || manifest.models[0].id, want.vs);
}

// Fraction of non-background pixels in each pane: a pane showing nothing is a failure the console does not report.
function coverage() {
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(4 * w * h);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const cover = [0, 0];
  for (let y = 0; y < h; y++)
    for (let x = 0; x < w; x++) {
      const o = 4 * (y * w + x);
      if (px[o] < 250 || px[o + 1] < 250 || px[o + 2] < 250) cover[x < w / 2 ? 0 : 1]++;
    }
  return cover.map((c) => c / (w * h / 2));
}

function set(options) {
  Object.assign(state, options);
  restyle();
}

if (!manifest) {
  window.CDP_VIEWER_MISSING("data/manifest.js (the meshes)");
} else {
  const ready = start();
  const view = () => ({ position: camera.position.toArray(), distance: camera.position.distanceTo(controls.target) });
  window.cdpViewer = { manifest, ready, show, set, coverage, view, loaded, errors, state };
}
