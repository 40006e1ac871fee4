// footfall teach: label the foothold the robot should have chosen (paper §II-B, Fig. 3a).
// World frame: x forward, y left, z up, metres. The server snaps a click to the nearest
// candidate of F; every label is stored at once.
import * as THREE from "three";
import { OrbitControls } from "three/addons/OrbitControls.js";

const TOKEN = new URLSearchParams(location.search).get("token");
const $ = (id) => document.getElementById(id);
const state = { runs: [], run: null, order: [], pos: 0, step: null, labeler: "" };

// ------------------------------------------------------------------ the API
async function api(path, options = {}) {
  const headers = { "Content-Type": "application/json" };
  if (TOKEN) headers.Authorization = "token " + TOKEN;
  const response = await fetch(path, { ...options, headers, credentials: "same-origin" });
  const body = await response.json().catch(() => ({ detail: response.statusText }));
  if (!response.ok) throw new Error(body.detail || response.statusText);
  return body;
}

function say(text, error = false) {
  $("message").textContent = text;
  $("message").className = error ? "error" : "";
}

function labeler() {
  let name = $("labeler").value.trim();
  if (!name) {
    name = (prompt("Your name, to sign your labels:") || "").trim();
    $("labeler").value = name;
  }
  if (name) localStorage.setItem("footfall-labeler", name);
  return name;
}

function requestId() {
  const bytes = new Uint8Array(12);
  crypto.getRandomValues(bytes);
  return Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
}

// --------------------------------------------------------------- runs list
async function loadRuns() {
  state.runs = await api("/api/runs");
  const body = $("runs").querySelector("tbody");
  body.replaceChildren();
  for (const r of state.runs) {
    const tr = document.createElement("tr");
    tr.dataset.run = r.id;
    const cells = [r.id, r.key ?? "", r.board, r.chooser,
      r.success ? "crossed" : (r.reason ?? "failed"),
      r.slip_mean_mm == null ? "-" : r.slip_mean_mm.toFixed(1), r.steps, r.labels];
    cells.forEach((c, i) => {
      const td = document.createElement("td");
      td.textContent = c;
      if (i === 4 && !r.success) td.className = "fail";
      tr.append(td);
    });
    tr.addEventListener("click", () => openRun(r.id));
    body.append(tr);
  }
  if (state.run) markRun(state.run.id);
}

function markRun(id) {
  for (const tr of $("runs").querySelectorAll("tbody tr"))
    tr.classList.toggle("current", Number(tr.dataset.run) === id);
}

async function refreshCounts() {
  const c = await api("/api/counts");
  const names = Object.entries(c.labels.by_labeler)
    .map(([n, v]) => `${n}: ${v.foothold} footholds, ${v.fine} fine`).join("; ");
  $("counts").textContent = `labels: ${names || "none yet"}` +
    (c.labels.disagreements ? `; labelers disagree on ${c.labels.disagreements} steps` : "");
}

// -------------------------------------------------------------------- a run
async function openRun(id) {
  say("judging the run's steps ...");
  state.run = await api(`/api/runs/${id}`);
  markRun(id);
  setOrder();
  $("step-panel").hidden = false;
  await showStep(0);
  say("");
}

function setOrder() {
  const n = state.run.steps.length;
  state.order = $("order").value === "look" ? state.run.order : [...Array(n).keys()];
}

async function showStep(pos) {
  if (!state.run || !state.order.length) return;
  state.pos = Math.max(0, Math.min(pos, state.order.length - 1));
  const k = state.order[state.pos];
  state.step = await api(`/api/runs/${state.run.id}/steps/${k}`);
  drawStep();
}

function drawStep() {
  const s = state.step;
  const facts = [`leg ${s.leg}`, `${s.candidates.length} candidates`,
    s.slip_mm == null ? "slip not measured" : `slip ${s.slip_mm.toFixed(1)} mm`,
    s.steps_to_fall == null ? `run ended: ${s.reason}` :
      (s.steps_to_fall === 0 ? "fell at this step" : `fell ${s.steps_to_fall} steps later`),
    `expert's shortfall ${s.shortfall.toFixed(1)} (its best: green)`];
  $("step-title").textContent =
    `run ${s.run}, step ${s.k} of ${s.steps} (${state.pos + 1} / ${state.order.length} in this order)`;
  $("facts").textContent = facts.join(" · ");
  const mine = s.labels.filter((l) => l.labeler === $("labeler").value.trim());
  $("labels").textContent = s.labels.length ? "labels: " + s.labels.map((l) =>
    `${l.labeler}: ${l.verdict === "fine" ? "fine" : "candidate " + l.chosen}`).join("; ") :
    "no labels yet";
  $("undo").disabled = mine.length === 0;
  view3d.show(s);
  drawTop(s);
}

// ------------------------------------------------------------------ labelling
async function label(body) {
  const name = labeler();
  if (!name) { say("a label needs your name", true); return; }
  try {
    const stored = await api("/api/labels", {
      method: "POST",
      body: JSON.stringify({ run: state.step.run, step: state.step.k, labeler: name,
                             request: requestId(), ...body }),
    });
    // The page knows its own label at once (an undo right away finds it), then refreshes.
    state.step.labels = [...state.step.labels.filter((l) => l.labeler !== name), stored];
    drawStep();
    say(stored.verdict === "fine" ? "saved: the robot's choice was fine"
                                  : `saved: candidate ${stored.chosen}`);
    await afterChange();
  } catch (e) { say(e.message, true); }
}

async function undo() {
  const name = $("labeler").value.trim();
  const mine = state.step.labels.filter((l) => l.labeler === name);
  if (!mine.length) return;
  try {
    const gone = mine[mine.length - 1].id;
    await api(`/api/labels/${gone}?labeler=${encodeURIComponent(name)}`, { method: "DELETE" });
    state.step.labels = state.step.labels.filter((l) => l.id !== gone);
    drawStep();
    say("label removed");
    await afterChange();
  } catch (e) { say(e.message, true); }
}

async function afterChange() {  // others may have labelled this step meanwhile
  const { run, k } = state.step;
  const fresh = await api(`/api/runs/${run}/steps/${k}`);
  if (state.step.run === run && state.step.k === k) { state.step = fresh; drawStep(); }
  await Promise.all([refreshCounts(), loadRuns()]);
}

// ------------------------------------------------------------------ colours
function rewardColours(rewards) {
  const finite = rewards.filter((r) => r !== null);
  const lo = Math.min(...finite), hi = Math.max(...finite);
  const low = new THREE.Color("#3b4cc0"), mid = new THREE.Color("#dddddd"),
    high = new THREE.Color("#f7d13d");
  return rewards.map((r) => {
    if (r === null) return new THREE.Color("#9e9e9e");
    const t = hi > lo ? (r - lo) / (hi - lo) : 1;
    return t < 0.5 ? low.clone().lerp(mid, 2 * t) : mid.clone().lerp(high, 2 * t - 1);
  });
}

function heightRange(heights) {
  let lo = Infinity, hi = -Infinity;
  for (const row of heights) for (const h of row) if (h !== null) {
    lo = Math.min(lo, h); hi = Math.max(hi, h);
  }
  return lo <= hi ? [lo, hi] : [0, 0];
}

// ------------------------------------------------------------------ 3D view
const view3d = (() => {
  const box = $("view3d");
  let renderer = null;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    box.textContent = "The 3D view needs WebGL, which this browser lacks; the top view works.";
    return { show() {}, screenOf() { return null; }, ok: false };
  }
  renderer.setPixelRatio(window.devicePixelRatio);
  box.append(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color("#eceff1");
  const camera = new THREE.PerspectiveCamera(40, 4 / 3, 0.005, 20);
  camera.up.set(0, 0, 1);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.addEventListener("change", render);
  scene.add(new THREE.AmbientLight(0xffffff, 1.2));
  const sun = new THREE.DirectionalLight(0xffffff, 2.0);
  sun.position.set(0.5, 0.8, 2.0);
  scene.add(sun);
  let group = null, terrain = null, candidates = [], framedRun = null;

  function render() { renderer.render(scene, camera); }

  function fit() {  // the panel was hidden when the page loaded: size the canvas when shown
    const w = box.clientWidth, h = box.clientHeight, size = renderer.getSize(new THREE.Vector2());
    if (w > 0 && h > 0 && (size.x !== w || size.y !== h)) {
      renderer.setSize(w, h);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
    }
  }

  function sphere(p, radius, colour) {
    const m = new THREE.Mesh(new THREE.SphereGeometry(radius, 16, 12),
                             new THREE.MeshStandardMaterial({ color: colour }));
    m.position.set(p[0], p[1], p[2] + radius);
    return m;
  }

  function terrainMesh(t) {
    const nx = t.x.length, ny = t.y.length, [lo, hi] = heightRange(t.heights);
    const pos = new Float32Array(nx * ny * 3), col = new Float32Array(nx * ny * 3);
    const index = [];
    const a = new THREE.Color("#5d6d4e"), b = new THREE.Color("#d7ccc8"), c = new THREE.Color();
    for (let i = 0; i < nx; i++) for (let j = 0; j < ny; j++) {
      const h = t.heights[i][j], v = i * ny + j;
      pos.set([t.x[i], t.y[j], h === null ? lo : h], 3 * v);
      c.copy(a).lerp(b, hi > lo && h !== null ? (h - lo) / (hi - lo) : 0);
      col.set([c.r, c.g, c.b], 3 * v);
    }
    for (let i = 0; i + 1 < nx; i++) for (let j = 0; j + 1 < ny; j++) {
      const q = [i * ny + j, (i + 1) * ny + j, (i + 1) * ny + j + 1, i * ny + j + 1];
      if ([[i, j], [i + 1, j], [i + 1, j + 1], [i, j + 1]].some(([u, w]) => t.heights[u][w] === null))
        continue;  // no data here: a hole in the mesh
      index.push(q[0], q[1], q[2], q[0], q[2], q[3]);
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.BufferAttribute(pos, 3));
    g.setAttribute("color", new THREE.BufferAttribute(col, 3));
    g.setIndex(index);
    g.computeVertexNormals();
    return new THREE.Mesh(g, new THREE.MeshStandardMaterial({ vertexColors: true,
      side: THREE.DoubleSide, roughness: 0.9 }));
  }

  function robot(r) {
    const g = new THREE.Group();
    const trunk = new THREE.Mesh(new THREE.BoxGeometry(...r.body.size),
      new THREE.MeshStandardMaterial({ color: "#607d8b", transparent: true, opacity: 0.55 }));
    trunk.position.set(...r.body.position);
    trunk.rotation.copy(new THREE.Euler(r.body.rpy[0], r.body.rpy[1], r.body.rpy[2], "ZYX"));
    g.add(trunk);
    for (const [name, leg] of Object.entries(r.legs)) {
      const swing = name === r.swing_leg;
      const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(
        [new THREE.Vector3(...leg.hip), new THREE.Vector3(...leg.foot)]),
        new THREE.LineBasicMaterial({ color: swing ? "#fbc02d" : "#37474f" }));
      g.add(line);
      g.add(sphere([leg.foot[0], leg.foot[1], leg.foot[2]], r.foot_radius * 0.8,
                   swing ? "#fbc02d" : "#37474f"));
    }
    return g;
  }

  function show(s) {
    fit();
    if (group) scene.remove(group);
    group = new THREE.Group();
    terrain = terrainMesh(s.terrain);
    group.add(terrain);
    group.add(robot(s.robot));
    const colours = rewardColours(s.rewards);
    candidates = s.candidates.map((p, i) => {
      const m = sphere(p, 0.0025, colours[i]);
      m.userData.index = i;
      group.add(m);
      return m;
    });
    group.add(sphere(s.candidates[s.chosen], 0.006, "#e53935"));
    group.add(sphere(s.candidates[s.expert_best], 0.004, "#43a047"));
    const name = $("labeler").value.trim();
    for (const l of s.labels) if (l.verdict === "foothold")
      group.add(sphere(s.candidates[l.chosen], l.labeler === name ? 0.007 : 0.005,
                       l.labeler === name ? "#e0f7fa" : "#ff9800"));
    scene.add(group);
    const f = s.candidates[s.chosen], b = s.robot.body.position;
    if (framedRun !== `${s.run}/${s.k}`) {  // a new step: the robot and its foothold in view
      const t = [(f[0] + b[0]) / 2, (f[1] + b[1]) / 2, f[2]];
      controls.target.set(...t);
      camera.position.set(t[0] - 0.3, t[1] - 0.42, t[2] + 0.42);
      framedRun = `${s.run}/${s.k}`;
    }
    controls.update();
    render();
  }

  const ray = new THREE.Raycaster(), ndc = new THREE.Vector2();
  let down = null;
  renderer.domElement.addEventListener("pointerdown", (e) => { down = [e.clientX, e.clientY]; });
  renderer.domElement.addEventListener("pointerup", (e) => {
    if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4 || !terrain) return;
    const rect = renderer.domElement.getBoundingClientRect();
    ndc.set(((e.clientX - rect.left) / rect.width) * 2 - 1,
            -((e.clientY - rect.top) / rect.height) * 2 + 1);
    ray.setFromCamera(ndc, camera);
    const hit = ray.intersectObjects([...candidates, terrain], false)[0];
    if (!hit) return;
    if (hit.object.userData.index !== undefined)
      label({ verdict: "foothold", candidate: hit.object.userData.index });
    else label({ verdict: "foothold", point: [hit.point.x, hit.point.y] });
  });

  function screenOf(i) {  // CSS pixels of candidate i within the 3D view (for tests)
    const p = candidates[i].position.clone().project(camera);
    return { x: (p.x + 1) / 2 * box.clientWidth, y: (1 - p.y) / 2 * box.clientHeight };
  }
  return { show, screenOf, ok: true };
})();

// ------------------------------------------------------------------ top view
const TOP_MARGIN = 0.02;  // [m] shown around the candidate set in the top view

function topFrame(s) {  // the square around F (and a margin) that the top view shows [m]
  const xs = s.candidates.map((p) => p[0]), ys = s.candidates.map((p) => p[1]);
  const cx = (Math.min(...xs) + Math.max(...xs)) / 2, cy = (Math.min(...ys) + Math.max(...ys)) / 2;
  const half = Math.max(Math.max(...xs) - Math.min(...xs), Math.max(...ys) - Math.min(...ys)) / 2
    + TOP_MARGIN;
  return { x0: cx - half, x1: cx + half, y0: cy - half, y1: cy + half };
}

function toPixel(s, x, y) {
  const f = topFrame(s), c = $("top");
  return { x: (x - f.x0) / (f.x1 - f.x0) * c.width, y: (f.y1 - y) / (f.y1 - f.y0) * c.height };
}

function drawTop(s) {
  const c = $("top"), g = c.getContext("2d"), t = s.terrain;
  const [lo, hi] = heightRange(t.heights);
  g.clearRect(0, 0, c.width, c.height);
  const f = topFrame(s), px = c.width / (f.x1 - f.x0) * t.step;  // a sample's side [pixels]
  for (let i = 0; i < t.x.length; i++) for (let j = 0; j < t.y.length; j++) {
    const h = t.heights[i][j], q = toPixel(s, t.x[i], t.y[j]);
    if (q.x < -px || q.y < -px || q.x > c.width + px || q.y > c.height + px) continue;
    const v = h === null ? 0 : Math.round(60 + 180 * (hi > lo ? (h - lo) / (hi - lo) : 0.5));
    g.fillStyle = h === null ? "#b71c1c" : `rgb(${v},${v},${v})`;
    g.fillRect(q.x - px / 2, q.y - px / 2, px + 0.5, px + 0.5);
  }
  const dot = (p, r, fill, stroke) => {
    const q = toPixel(s, p[0], p[1]);
    g.beginPath(); g.arc(q.x, q.y, r, 0, 2 * Math.PI);
    if (fill) { g.fillStyle = fill; g.fill(); }
    if (stroke) { g.strokeStyle = stroke; g.lineWidth = 1.5; g.stroke(); }
  };
  const colours = rewardColours(s.rewards);
  s.candidates.forEach((p, i) => dot(p, 4, "#" + colours[i].getHexString()));
  for (const [name, leg] of Object.entries(s.robot.legs))
    dot(leg.foot, 5, null, name === s.robot.swing_leg ? "#fbc02d" : "#263238");
  dot(s.candidates[s.expert_best], 6, "#43a047");
  dot(s.candidates[s.chosen], 7, "#e53935");
  const name = $("labeler").value.trim();
  for (const l of s.labels) if (l.verdict === "foothold")
    dot(s.candidates[l.chosen], l.labeler === name ? 8 : 6,
        l.labeler === name ? "#e0f7fa" : "#ff9800", "#006064");
}

$("top").addEventListener("click", (e) => {
  if (!state.step) return;
  const c = $("top"), rect = c.getBoundingClientRect(), f = topFrame(state.step);
  const px = (e.clientX - rect.left) * c.width / rect.width;
  const py = (e.clientY - rect.top) * c.height / rect.height;
  label({ verdict: "foothold", point: [f.x0 + px / c.width * (f.x1 - f.x0),
                                       f.y1 - py / c.height * (f.y1 - f.y0)] });
});

// ------------------------------------------------------------------ controls
$("prev").addEventListener("click", () => showStep(state.pos - 1));
$("next").addEventListener("click", () => showStep(state.pos + 1));
$("skip").addEventListener("click", () => showStep(state.pos + 1));
$("fine").addEventListener("click", () => label({ verdict: "fine" }));
$("undo").addEventListener("click", undo);
$("order").addEventListener("change", () => { if (state.run) { setOrder(); showStep(0); } });
$("labeler").addEventListener("change", () => {
  localStorage.setItem("footfall-labeler", $("labeler").value.trim());
  if (state.step) drawStep();
});
document.addEventListener("keydown", (e) => {
  if (e.target.tagName === "INPUT" || e.target.tagName === "SELECT" || !state.step) return;
  const keys = { ArrowLeft: () => showStep(state.pos - 1), ArrowRight: () => showStep(state.pos + 1),
    f: () => label({ verdict: "fine" }), s: () => showStep(state.pos + 1), u: undo };
  if (keys[e.key]) { e.preventDefault(); keys[e.key](); }
});

// For tests and scripts: where a candidate is drawn (CSS pixels in each view).
window.teach = {
  state,
  pixelOf(i) {
    const c = $("top"), rect = c.getBoundingClientRect(), s = state.step;
    const q = toPixel(s, s.candidates[i][0], s.candidates[i][1]);
    return { x: q.x * rect.width / c.width, y: q.y * rect.height / c.height };
  },
  screenOf3D(i) { return view3d.ok ? view3d.screenOf(i) : null; },
  has3D: view3d.ok,
};

(async () => {
  try {
    const session = await api("/api/session");
    $("store").textContent = session.store;
    $("labeler").value = session.labeler || localStorage.getItem("footfall-labeler") || "";
    await Promise.all([loadRuns(), refreshCounts()]);
    document.body.dataset.ready = "yes";
  } catch (e) { say(e.message, true); }
})();
