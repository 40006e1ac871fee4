// footfall teach: the 3D view of a step (three.js). World frame x forward, y left, z up,
// metres. The terrain and the robot are built once per step; the marks are pins over their
// candidates ("never here" marks are crosses), stacked one above the other so that none hides
// another. Drag orbits, the wheel
// zooms; the camera stays above the ground, and reset() frames the step again.
import * as THREE from "three";
import { OrbitControls } from "three/addons/OrbitControls.js";
import { COLOURS, rewardColours } from "./marks.js";
import { heightRange } from "./topview.js";

const PIN_GAP = 0.009;     // [m] between stacked pins
const ABOVE_GROUND = 0.02; // [m] the camera is kept at least this far above the terrain
const DRAG = 4;            // [CSS px] farther than this is an orbit, not a click
const CANDIDATE = 0.0025;  // [m] radius of a candidate's ball

export function createView3D(box, onLabel) {
  let renderer = null;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: false });
  } catch (e) {
    box.textContent = "The 3D view needs WebGL, which this browser lacks; the top view works.";
    return { ok: false, setStep() {}, setMarks() {}, reset() {}, screenOf() { return null; },
             camera() { return null; }, ground() { return null; }, pick() { return null; } };
  }
  renderer.setPixelRatio(window.devicePixelRatio);
  box.append(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color("#eceff1");
  const camera = new THREE.PerspectiveCamera(40, 4 / 3, 0.005, 20);
  camera.up.set(0, 0, 1);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.maxPolarAngle = 0.47 * Math.PI;  // never below the horizon of the target
  controls.minDistance = 0.05;
  controls.maxDistance = 3;
  scene.add(new THREE.AmbientLight(0xffffff, 1.2));
  const sun = new THREE.DirectionalLight(0xffffff, 2.0);
  sun.position.set(0.5, 0.8, 2.0);
  scene.add(sun);
  let world = null, marks = null, terrain = null, candidates = null, step = null, home = null;
  warmUp();

  function warmUp() {  // compile the shaders a step needs now, not when the first step is shown
    const h = [[0, 0], [0, 0]];
    const s = { terrain: { x: [0, 0.01], y: [0, 0.01], heights: h, step: 0.01 },
                candidates: [[0, 0, 0]], rewards: [1] };
    const warm = new THREE.Group();
    warm.add(terrainMesh(s.terrain), candidateMesh(s), sphere([0, 0, 0], 0.01, "#fff"));
    warm.add(new THREE.Mesh(new THREE.BoxGeometry(0.01, 0.01, 0.01),
      new THREE.MeshLambertMaterial({ color: "#607d8b", transparent: true, opacity: 0.55 })));
    warm.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(
      [new THREE.Vector3(0, 0, 0), new THREE.Vector3(0, 0, 0.01)]), new THREE.LineBasicMaterial()));
    scene.add(warm);
    camera.position.set(0.03, 0.03, 0.03);  // looking at it: every shader draws a pixel
    camera.lookAt(0, 0, 0);
    renderer.compile(scene, camera);
    renderer.render(scene, camera);  // and draw once: the software GL compiles its pipelines
    dispose(warm);
  }

  function render() { renderer.render(scene, camera); }

  function groundAt(x, y) {  // [m] the terrain's height under (x, y), null off the window
    const t = step && step.terrain;
    if (!t) return null;
    const i = Math.round((x - t.x[0]) / t.step), j = Math.round((y - t.y[0]) / t.step);
    if (i < 0 || j < 0 || i >= t.x.length || j >= t.y.length) return null;
    return t.heights[i][j];
  }

  controls.addEventListener("change", () => {
    const g = groundAt(camera.position.x, camera.position.y);
    if (g !== null && camera.position.z < g + ABOVE_GROUND) camera.position.z = g + ABOVE_GROUND;
    render();
  });

  function fit() {  // the canvas follows its box (the panel may have been hidden, or resized)
    const w = box.clientWidth, h = box.clientHeight, size = renderer.getSize(new THREE.Vector2());
    if (w > 0 && h > 0 && (size.x !== w || size.y !== h)) {
      renderer.setSize(w, h);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
      return true;
    }
    return false;
  }
  new ResizeObserver(() => { if (fit() && step) render(); }).observe(box);

  function sphere(p, radius, colour, lift = 0) {
    const m = new THREE.Mesh(new THREE.SphereGeometry(radius, 16, 12),
                             new THREE.MeshLambertMaterial({ color: colour }));
    m.position.set(p[0], p[1], p[2] + radius + lift);
    return m;
  }

  // The terrain as one mesh; `mesh` given (the previous step's), its buffers are refilled in
  // place when the grid has the same size: no new GL buffers for each step.
  function terrainMesh(t, mesh = null) {
    const nx = t.x.length, ny = t.y.length, [lo, hi] = heightRange(t.heights);
    const g = mesh && mesh.userData.cells === nx * ny ? mesh.geometry : new THREE.BufferGeometry();
    const fresh = g !== (mesh && mesh.geometry);
    const pos = fresh ? new Float32Array(nx * ny * 3) : g.attributes.position.array;
    const col = fresh ? new Float32Array(nx * ny * 3) : g.attributes.color.array;
    const a = new THREE.Color("#5d6d4e"), b = new THREE.Color("#d7ccc8"), c = new THREE.Color();
    for (let i = 0; i < nx; i++) for (let j = 0; j < ny; j++) {
      const h = t.heights[i][j], v = 3 * (i * ny + j);
      pos[v] = t.x[i]; pos[v + 1] = t.y[j]; pos[v + 2] = h === null ? lo : h;
      c.copy(a).lerp(b, hi > lo && h !== null ? (h - lo) / (hi - lo) : 0);
      col[v] = c.r; col[v + 1] = c.g; col[v + 2] = c.b;
    }
    const index = [];
    for (let i = 0; i + 1 < nx; i++) for (let j = 0; j + 1 < ny; j++) {
      if (t.heights[i][j] === null || t.heights[i + 1][j] === null ||
          t.heights[i + 1][j + 1] === null || t.heights[i][j + 1] === null) continue;  // a hole
      const q = i * ny + j;
      index.push(q, q + ny, q + ny + 1, q, q + ny + 1, q + 1);
    }
    if (fresh) {
      g.setAttribute("position", new THREE.BufferAttribute(pos, 3));
      g.setAttribute("color", new THREE.BufferAttribute(col, 3));
    } else {
      g.attributes.position.needsUpdate = true;
      g.attributes.color.needsUpdate = true;
    }
    if (!fresh && g.index && g.index.count === index.length) {
      g.index.array.set(index);
      g.index.needsUpdate = true;
    } else {
      g.setIndex(index);
    }
    g.computeVertexNormals();
    g.computeBoundingSphere();
    g.computeBoundingBox();
    if (!fresh) return mesh;
    if (mesh) mesh.geometry.dispose();
    const made = mesh || new THREE.Mesh(g, new THREE.MeshLambertMaterial({ vertexColors: true,
      side: THREE.DoubleSide }));
    made.geometry = g;
    made.userData.cells = nx * ny;
    return made;
  }

  function robot(r) {
    const g = new THREE.Group();
    const trunk = new THREE.Mesh(new THREE.BoxGeometry(...r.body.size),
      new THREE.MeshLambertMaterial({ color: "#607d8b", transparent: true, opacity: 0.55 }));
    trunk.position.set(...r.body.position);
    trunk.rotation.copy(new THREE.Euler(r.body.rpy[0], r.body.rpy[1], r.body.rpy[2], "ZYX"));
    g.add(trunk);
    for (const [name, leg] of Object.entries(r.legs)) {
      const colour = name === r.swing_leg ? COLOURS.swing : COLOURS.stance;
      g.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(
        [new THREE.Vector3(...leg.hip), new THREE.Vector3(...leg.foot)]),
        new THREE.LineBasicMaterial({ color: colour })));
      g.add(sphere(leg.foot, r.foot_radius * 0.8, colour));
    }
    return g;
  }

  function cross(p, kind, lift) {  // "never here": two flat bars crossed over the candidate
    const group = new THREE.Group(), mine = kind === "never_mine";
    const size = mine ? 0.016 : 0.014, bar = mine ? 0.003 : 0.0024;
    for (const angle of mine ? [Math.PI / 4, -Math.PI / 4] : [0, Math.PI / 2]) {
      const m = new THREE.Mesh(new THREE.BoxGeometry(size, bar, bar),
                               new THREE.MeshLambertMaterial({ color: COLOURS[kind] }));
      m.rotation.z = angle;
      group.add(m);
    }
    group.position.set(p[0], p[1], p[2] + 2 * CANDIDATE + lift);
    return group;
  }

  function candidateMesh(s) {  // F as one instanced mesh: one draw call for every candidate
    const colours = rewardColours(s.rewards);
    const mesh = new THREE.InstancedMesh(new THREE.SphereGeometry(CANDIDATE, 10, 8),
                                         new THREE.MeshLambertMaterial(), s.candidates.length);
    const m = new THREE.Matrix4(), c = new THREE.Color();
    s.candidates.forEach((p, i) => {
      mesh.setMatrixAt(i, m.makeTranslation(p[0], p[1], p[2] + CANDIDATE));
      mesh.setColorAt(i, c.set(colours[i]));
    });
    return mesh;
  }

  function dispose(group) {
    if (!group) return;
    scene.remove(group);
    group.traverse((o) => { o.geometry?.dispose(); o.material?.dispose(); });
  }

  function setStep(s, stepMarks) {
    fit();
    if (world && terrain) world.remove(terrain);  // kept: refilled for the new step
    dispose(world);
    step = s;
    world = new THREE.Group();
    terrain = terrainMesh(s.terrain, terrain);
    world.add(terrain);
    world.add(robot(s.robot));
    candidates = candidateMesh(s);
    world.add(candidates);
    scene.add(world);
    const f = s.candidates[s.chosen], b = s.robot.body.position;
    const target = [(f[0] + b[0]) / 2, (f[1] + b[1]) / 2, f[2]];
    home = { target, position: [target[0] - 0.28, target[1] - 0.36, target[2] + 0.5] };
    setMarks(stepMarks, false);
    reset();
  }

  function setMarks(list, draw = true) {
    dispose(marks);
    marks = new THREE.Group();
    const levels = new Map();  // candidate -> pins stacked on it so far
    for (const m of [...list].reverse()) {  // innermost (expert) lowest, others' on top
      const p = step.candidates[m.index];
      const level = levels.get(m.index) || 0;
      for (let n = 0; n < m.count; n++) {
        const lift = PIN_GAP * (level + n), never = m.kind.startsWith("never");
        const pin = never ? cross(p, m.kind, lift) :
          sphere(p, m.kind === "mine" ? 0.0045 : 0.0038, COLOURS[m.kind], lift);
        pin.traverse((o) => { o.userData.index = m.index; });
        marks.add(pin);
      }
      levels.set(m.index, level + m.count);
    }
    scene.add(marks);
    if (draw) render();
  }

  function reset() {
    if (!home) return;
    controls.target.set(...home.target);
    camera.position.set(...home.position);
    controls.update();
    render();
  }

  // What is under the client point (x, y) [CSS px]: {candidate} (a candidate or a mark on one),
  // {point} (x, y [m] on the terrain), or null (the sky, or no step yet).
  const ray = new THREE.Raycaster(), ndc = new THREE.Vector2();
  function pick(x, y) {
    if (!terrain) return null;
    const rect = renderer.domElement.getBoundingClientRect();
    ndc.set(((x - rect.left) / rect.width) * 2 - 1, -((y - rect.top) / rect.height) * 2 + 1);
    ray.setFromCamera(ndc, camera);
    const hit = ray.intersectObjects([candidates, ...(marks ? marks.children : []), terrain],
                                     true)[0];
    if (!hit) return null;
    if (hit.object === candidates) return { candidate: hit.instanceId };
    if (hit.object.userData.index !== undefined) return { candidate: hit.object.userData.index };
    return { point: [hit.point.x, hit.point.y] };
  }

  let down = null;
  renderer.domElement.addEventListener("pointerdown", (e) => { down = [e.clientX, e.clientY]; });
  renderer.domElement.addEventListener("pointerup", (e) => {
    if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > DRAG || !terrain) return;
    down = null;
    const what = pick(e.clientX, e.clientY);
    if (what) onLabel(what);
  });

  function screenOf(i) {  // CSS pixels of candidate i within the view (for tests)
    const c = step.candidates[i];
    const p = new THREE.Vector3(c[0], c[1], c[2] + CANDIDATE).project(camera);
    return { x: (p.x + 1) / 2 * box.clientWidth, y: (1 - p.y) / 2 * box.clientHeight };
  }

  function cameraNow() {
    return { position: camera.position.toArray(), target: controls.target.toArray() };
  }

  return { ok: true, setStep, setMarks, reset, screenOf, camera: cameraNow, ground: groundAt,
           home: () => home, pick };
}
