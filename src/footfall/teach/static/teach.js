// footfall teach: label the foothold the robot should have chosen (paper §II-B, Fig. 3a), and
// mark the candidates it must never take (X). World frame: x forward, y left, z up, metres. The
// server snaps a click to the nearest candidate of F; every label and mark is stored at once.
// A run opens at its first step straight away (the synthetic expert judges its steps in the
// background); steps are fetched ahead.
import { ServerDown, api, onBusy, onLink, requestId } from "./api.js";
import { agreementText, countsText } from "./figures.js";
import { TOP_SIZE, stepMarks } from "./marks.js";
import { Pointer } from "./pointer.js";
import { fillRuns } from "./runslist.js";
import { TopView } from "./topview.js";
import { createView3D } from "./view3d.js";

const $ = (id) => document.getElementById(id);
const POLL = 2000;        // [ms] between looks for others' labels of the shown step
const REFRESH = 3;        // polls between refreshes of the counts, runs and agreement
const NARROW = 1100;      // [CSS px] below this the runs list folds away once a run is open
const HISTORY = 12;       // my last labels listed
const state = { runs: [], run: null, order: [], pos: 0, shownPos: -1, step: null, nav: 0,
                runSeq: 0, cache: new Map(), judging: false, history: [], timings: [],
                actions: new Map() };  // "run:k" -> my actions on that step, newest last (U)

// ------------------------------------------------------------------ status
function say(text, error = false) {
  $("message").textContent = text;
  $("message").className = error ? "error" : "";
}

function fail(e) {
  say(e.message, true);
  if (e instanceof ServerDown) document.body.classList.add("offline");
}

onBusy((n) => { document.body.classList.toggle("busy", n > 0); });
onLink((up) => {
  document.body.classList.toggle("offline", !up);
  if (up && $("message").className === "error" && $("message").textContent.includes("not answering"))
    say("the teaching server answers again");
});

function me() { return $("labeler").value.trim(); }

function askName() {
  let name = me();
  if (!name) {
    name = (prompt("Your name, to sign your labels:") || "").trim();
    $("labeler").value = name;
  }
  if (name) localStorage.setItem("footfall-labeler", name);
  return name;
}

function timed(what, start, then = null) {  // [ms] from start to the next painted frame
  requestAnimationFrame(() => setTimeout(() => {
    state.timings.push({ what, ms: performance.now() - start });
    if (then) then();
  }, 0));
}

// ------------------------------------------------------------------ runs list
async function loadRuns(quiet = false) {
  state.runs = await api("/api/runs", { quiet });
  fillRuns($("runs").querySelector("tbody"), state.runs, me(), openRun);
  if (state.run) markRun(state.run.id);
}

function markRun(id) {
  for (const tr of $("runs").querySelectorAll("tbody tr"))
    tr.classList.toggle("current", Number(tr.dataset.run) === id);
}

async function refreshCounts(quiet = false) {
  $("counts").textContent = countsText(await api("/api/counts", { quiet }));
}

async function refreshAgreement(quiet = true) {
  $("agreement").textContent = agreementText(await api("/api/agreement", { quiet }));
}

function setRunsOpen(open) {
  document.body.classList.toggle("runs-closed", !open);
  $("runs-toggle").setAttribute("aria-expanded", String(open));
}

// -------------------------------------------------------------------- a run
async function openRun(id) {
  const seq = ++state.runSeq, start = performance.now();
  say(`opening run ${id} ...`);
  try {
    const run = await api(`/api/runs/${id}?judge=false`);  // at once: no expert yet
    if (seq !== state.runSeq) return;
    state.run = run;
    state.cache = new Map();
    markRun(id);
    setOrder();
    $("step-panel").hidden = false;
    document.body.classList.add("run-open");
    if (window.innerWidth < NARROW) setRunsOpen(false);
    await showStep(0, "opening step view");
    if (seq !== state.runSeq) return;
    say("");
    // the expert judges once the first step is on screen: its work does not delay the view
    timed("first step", start, () => { if (seq === state.runSeq) judgeRun(id, seq); });
  } catch (e) { if (seq === state.runSeq) fail(e); }
}

async function judgeRun(id, seq) {  // the expert's verdicts, in the background
  state.judging = true;
  showJudging();
  try {
    const judged = await api(`/api/runs/${id}`, { quiet: true });
    if (seq !== state.runSeq) return;
    // The judged copy was read when the judging began: a label I gave (or undid) while the
    // expert judged is not in it. My part of each step's labellers is this page's; the
    // others' is the judged copy's.
    const name = me();
    const mine = new Map(state.run.steps.map((s) => [s.k, (s.labelers || []).includes(name)]));
    for (const s of judged.steps) {
      const others = (s.labelers || []).filter((n) => n !== name);
      s.labelers = mine.get(s.k) ? [...others, name] : others;
    }
    state.run = judged;
    if ($("order").value === "look") {  // the steps seen so far keep their places
      const seen = state.order.slice(0, state.shownPos + 1);
      state.order = [...seen, ...judged.order.filter((k) => !seen.includes(k))];
    }
    state.judging = false;
    if (state.step) drawStep(false);
  } catch (e) {
    if (seq === state.runSeq) fail(e);
  } finally {
    if (seq === state.runSeq) { state.judging = false; showJudging(); }
  }
}

function showJudging() {
  $("judging").hidden = !state.judging;
}

function setOrder() {
  const n = state.run.steps.length;
  state.order = $("order").value === "look" ? state.run.order : [...Array(n).keys()];
}

function runStep(k) { return state.run.steps.find((s) => s.k === k); }

function fetchStep(k) {
  if (!state.cache.has(k)) {
    const id = state.run.id;
    const request = api(`/api/runs/${id}/steps/${k}?judge=false`, { quiet: true });
    request.catch(() => state.cache.delete(k));  // a failed fetch is tried again next time
    state.cache.set(k, request);
  }
  return state.cache.get(k);
}

// `what`: the name its drawing time is recorded under (a run's first step is part of opening it)
async function showStep(pos, what = "step view") {
  if (!state.run || !state.order.length) return;
  state.pos = Math.max(0, Math.min(pos, state.order.length - 1));
  const seq = ++state.nav, shown = state.pos, k = state.order[shown];
  document.body.classList.add("loading-step");
  try {
    const step = await fetchStep(k);
    if (seq !== state.nav) return;  // a later move overtook this one: draw that one instead
    const start = performance.now();
    state.step = step;
    state.shownPos = shown;
    drawStep(true);
    timed(what, start, () => {  // then the next step, ahead of the labeller
      const next = state.order[shown + 1];
      if (next !== undefined && seq === state.nav) fetchStep(next);
    });
  } catch (e) {
    if (seq === state.nav) fail(e);
  } finally {
    if (seq === state.nav) document.body.classList.remove("loading-step");
  }
}

function expertBest(k) {
  const s = state.run && runStep(k);
  return s && s.expert_best !== null && s.expert_best !== undefined ? s.expert_best : null;
}

function marksNow() { return stepMarks(state.step, expertBest(state.step.k), me()); }

function drawStep(newStep) {
  const s = state.step, best = expertBest(s.k), info = runStep(s.k);
  const facts = [`leg ${s.leg}`, `${s.candidates.length} candidates`,
    s.slip_mm == null ? "slip not measured" : `slip ${s.slip_mm.toFixed(1)} mm`,
    s.steps_to_fall == null ? (s.failure ? `run failed: ${s.failure}` : "the run crossed") :
      (s.steps_to_fall === 0 ? `fell at this step (${s.failure})` :
        `fell ${s.steps_to_fall} steps later (${s.failure})`),
    best === null ? "the expert is judging the run ..." :
      `expert's shortfall ${info.shortfall === null ? "-" : info.shortfall.toFixed(1)}`];
  $("step-title").textContent = `run ${s.run}, step ${s.k} of ${s.steps} ` +
    `(${state.shownPos + 1} / ${state.order.length} in this order)`;
  $("facts").textContent = facts.join(" · ");
  drawLabels();
  drawBranches();
  if (newStep) {
    top.setStep(s, marksNow());
    view3d.setStep(s, marksNow());
  } else {
    top.setMarks(marksNow());
    view3d.setMarks(marksNow());
  }
}

function drawBranches() {  // what would have happened: the rollout teacher's branches here
  const s = state.step, b = s.branches, el = $("branches");
  el.replaceChildren();
  el.hidden = !b;
  if (!b) return;
  const head = document.createElement("div");
  head.textContent = "what would have happened (the rollout teacher's branches of this step):";
  const list = document.createElement("ul");
  for (const t of b.tried) {
    const roles = [t.candidate === s.chosen ? "the robot's choice" : null,
      t.candidate === b.taught ? "taught" : null].filter(Boolean);
    const li = document.createElement("li");
    li.textContent = `candidate ${t.candidate}${roles.length ? ` (${roles.join(", ")})` : ""}: ` +
      t.outcomes.join("; ");
    li.dataset.candidate = t.candidate;
    li.classList.toggle("taught", t.candidate === b.taught);
    list.append(li);
  }
  el.append(head, list);
}

function drawLabels() {  // the labels and marks text, the undo button, my progress in this run
  const s = state.step, name = me(), never = new Map();
  for (const m of s.marks) never.set(m.labeler, [...(never.get(m.labeler) || []), m.candidate]);
  $("labels").textContent = (s.labels.length ? "labels: " + s.labels.map((l) =>
    `${l.labeler}: ${l.verdict === "fine" ? "fine" : "candidate " + l.chosen}`).join("; ") :
    "no labels yet") + (never.size ? " · never here: " + [...never].map(([n, c]) =>
    `${n}: ${c.join(", ")}`).join("; ") : "");
  $("undo").disabled = !s.labels.some((l) => l.labeler === name) &&
    !s.marks.some((m) => m.labeler === name) && !actionsOf(s).length;
  const done = state.run.steps.filter((x) => (x.labelers || []).includes(name)).length;
  $("queue").textContent = name ? `${done} of ${state.run.steps.length} steps labelled by ${name}`
    : "give your name to label";
}

// ------------------------------------------------------------------ labelling
function setMine(step, label) {  // my label of a step, as the server now holds it (or none)
  const name = me();
  step.labels = [...step.labels.filter((l) => l.labeler !== name), ...(label ? [label] : [])];
  const info = state.run && state.run.id === step.run ? runStep(step.k) : null;
  if (info) {
    const others = (info.labelers || []).filter((n) => n !== name);
    info.labelers = label ? [...others, name] : others;
  }
}

function describe(l) { return l.verdict === "fine" ? "fine" : `candidate ${l.chosen}`; }

async function label(body) {
  const name = askName();
  if (!name) { say("a label needs your name", true); return; }
  const step = state.step;
  if (!step) return;
  try {
    const stored = await api("/api/labels", {
      method: "POST",
      body: JSON.stringify({ run: step.run, step: step.k, labeler: name, request: requestId(),
                             ...body }),
    });
    const start = performance.now();
    setMine(step, stored);
    if (state.step === step) { drawLabels(); top.setMarks(marksNow()); view3d.setMarks(marksNow()); }
    say(stored.verdict === "fine" ? "saved: the robot's choice was fine"
                                  : `saved: candidate ${stored.chosen}`);
    timed("label", start);
    remember(step, stored);
    actionsOf(step).push({ kind: "label" });
    refreshSoon();
  } catch (e) { fail(e); }
}

async function undo() {
  const step = state.step, name = me();
  const mine = step && step.labels.find((l) => l.labeler === name);
  if (!mine) return;
  try {
    const answer = await api(`/api/labels/${mine.id}?labeler=${encodeURIComponent(name)}`,
                             { method: "DELETE" });
    setMine(step, answer.restored);
    if (state.step === step) { drawLabels(); top.setMarks(marksNow()); view3d.setMarks(marksNow()); }
    say(answer.restored ? `label undone: back to ${describe(answer.restored)}` : "label removed");
    remember(step, answer.restored, true);
    refreshSoon();
  } catch (e) { fail(e); }
}

function remember(step, label, undone = false, what = null) {  // my history, newest first
  state.history.unshift({ run: step.run, k: step.k, what: what ?? (undone ?
    (label ? `undone, back to ${describe(label)}` : "undone") : describe(label)) });
  state.history.length = Math.min(state.history.length, HISTORY);
  const list = $("history");
  list.replaceChildren(...state.history.map((h) => {
    const li = document.createElement("li");
    const a = document.createElement("a");
    a.href = "#";
    a.textContent = `run ${h.run} step ${h.k}: ${h.what}`;
    a.addEventListener("click", (e) => { e.preventDefault(); goTo(h.run, h.k); });
    li.append(a);
    return li;
  }));
}

async function goTo(run, k) {
  if (!state.run || state.run.id !== run) await openRun(run);
  const pos = state.order.indexOf(k);
  if (pos >= 0) await showStep(pos);
}

function nextUnlabelled() {
  const name = me();
  for (let i = 1; i <= state.order.length; i++) {
    const pos = (state.shownPos + i) % state.order.length;
    if (!(runStep(state.order[pos]).labelers || []).includes(name)) return showStep(pos);
  }
  say("every step of this run has your label");
}

let refreshTimer = null;
function refreshSoon() {  // counts, runs and agreement, once the labeller pauses
  clearTimeout(refreshTimer);
  refreshTimer = setTimeout(() => {
    Promise.all([refreshCounts(true), loadRuns(true), refreshAgreement(true)]).catch(fail);
  }, 400);
}

// ------------------------------------------------------------- "never here" marks
function actionsOf(step) {  // my actions on a step this page took, newest last
  const key = `${step.run}:${step.k}`;
  if (!state.actions.has(key)) state.actions.set(key, []);
  return state.actions.get(key);
}

function myMark(step, candidate) {
  return step.marks.find((m) => m.labeler === me() && m.candidate === candidate);
}

function redrawMarks(step) {
  if (state.step !== step) return;
  drawLabels(); top.setMarks(marksNow()); view3d.setMarks(marksNow());
}

// X: the candidate under the pointer marked "never here", or my mark on it removed.
function markHere() {
  const name = askName();
  if (!name) { say("a mark needs your name", true); return; }
  const i = pointer.candidate(state.step);
  if (i === null) { say("no candidate near the pointer: point at one and press X", true); return; }
  return myMark(state.step, i) ? unmark(state.step, i) : mark(state.step, i);
}

async function mark(step, candidate, undoing = false) {
  try {
    const stored = await api("/api/marks", { method: "POST", body: JSON.stringify(
      { run: step.run, step: step.k, candidate, labeler: me(), request: requestId() }) });
    step.marks = [...step.marks.filter((m) => m.id !== stored.id), stored];
    if (!undoing) actionsOf(step).push({ kind: "mark", candidate });
    redrawMarks(step);
    const what = undoing ? `mark back: never candidate ${candidate}` :
      `never here: candidate ${candidate}`;
    say(what);
    remember(step, null, false, what);
    refreshSoon();
  } catch (e) { fail(e); }
}

async function unmark(step, candidate, undoing = false) {
  const mine = myMark(step, candidate);
  if (!mine) return;
  try {
    await api(`/api/marks/${mine.id}?labeler=${encodeURIComponent(me())}`, { method: "DELETE" });
    step.marks = step.marks.filter((m) => m.id !== mine.id);
    if (!undoing) actionsOf(step).push({ kind: "unmark", candidate });
    redrawMarks(step);
    const what = `${undoing ? "mark undone" : "mark removed"}: candidate ${candidate}`;
    say(what);
    remember(step, null, false, what);
    refreshSoon();
  } catch (e) { fail(e); }
}

// U: my last action on the step undone -- a label (my earlier one comes back), a mark (removed)
// or a mark's removal (marked again). The page's own record of them first; without one (a
// reload, another page), the newer of my label and my newest mark.
function undoLast() {
  const step = state.step, name = me();
  if (!step) return;
  const done = actionsOf(step);
  while (done.length) {
    const last = done.pop();
    if (last.kind === "label" && step.labels.some((l) => l.labeler === name)) return undo();
    if (last.kind === "mark" && myMark(step, last.candidate))
      return unmark(step, last.candidate, true);
    if (last.kind === "unmark" && !myMark(step, last.candidate))
      return mark(step, last.candidate, true);
  }
  const label = step.labels.find((l) => l.labeler === name);
  const marks = step.marks.filter((m) => m.labeler === name);
  const newest = marks.reduce((a, m) => (!a || m.created >= a.created ? m : a), null);
  if (newest && (!label || newest.created > label.created))
    return unmark(step, newest.candidate, true);
  if (label) return undo();
}

// ------------------------------------------------------------------ live updates
let ticks = 0;
async function poll() {
  if (document.hidden) return;
  ticks += 1;
  try {
    const step = state.step;
    if (step) {
      const now = await api(`/api/runs/${step.run}/steps/${step.k}/labels`, { quiet: true });
      if (state.step === step && JSON.stringify(now) !==
          JSON.stringify({ labels: step.labels, marks: step.marks })) {
        step.labels = now.labels;
        step.marks = now.marks;
        const info = runStep(step.k);
        if (info) info.labelers = now.labels.map((l) => l.labeler);
        drawLabels();
        top.setMarks(marksNow());
        view3d.setMarks(marksNow());
      }
    }
    if (ticks % REFRESH === 0)
      await Promise.all([refreshCounts(true), loadRuns(true), refreshAgreement(true)]);
  } catch (e) {
    if (e instanceof ServerDown) fail(e);
  }
}

// ------------------------------------------------------------------ the views
const top = new TopView($("top"), (x, y) => label({ verdict: "foothold", point: [x, y] }));
const view3d = createView3D($("view3d"), (what) => label({ verdict: "foothold", ...what }));
const pointer = new Pointer($("top"), $("view3d"), top, view3d);

function resetViews() { top.reset(); view3d.reset(); }

// The top view is square: as tall as the views' row, at most half its width.
new ResizeObserver(([entry]) => {
  const { width, height } = entry.contentRect;
  const side = Math.max(0, Math.floor(Math.min(height, width / 2)));
  $("top").style.width = $("top").style.height = `${side}px`;
}).observe($("views"));

// ------------------------------------------------------------------ controls
$("prev").addEventListener("click", () => showStep(state.pos - 1));
$("next").addEventListener("click", () => showStep(state.pos + 1));
$("skip").addEventListener("click", () => showStep(state.pos + 1));
$("unlabelled").addEventListener("click", nextUnlabelled);
$("fine").addEventListener("click", () => label({ verdict: "fine" }));
$("undo").addEventListener("click", undoLast);
$("reset-view").addEventListener("click", resetViews);
$("runs-toggle").addEventListener("click", () =>
  setRunsOpen(document.body.classList.contains("runs-closed")));
$("help-button").addEventListener("click", () => $("help").showModal());
$("help-close").addEventListener("click", () => $("help").close());
$("order").addEventListener("change", () => { if (state.run) { setOrder(); showStep(0); } });
$("labeler").addEventListener("change", () => {
  localStorage.setItem("footfall-labeler", me());
  if (state.step) drawLabels();
  if (state.step) { top.setMarks(marksNow()); view3d.setMarks(marksNow()); }
  loadRuns(true).catch(fail);
});
document.addEventListener("keydown", (e) => {
  if (e.target.tagName === "INPUT" || e.target.tagName === "SELECT") return;
  if (e.key === "?") { e.preventDefault(); $("help").open ? $("help").close() : $("help").showModal(); return; }
  if (!state.step || $("help").open) return;
  const keys = { ArrowLeft: () => showStep(state.pos - 1), ArrowRight: () => showStep(state.pos + 1),
    f: () => label({ verdict: "fine" }), s: () => showStep(state.pos + 1), u: undoLast,
    x: markHere, X: markHere,
    n: nextUnlabelled, r: resetViews, "+": () => top.zoomAbout(1.25, top.view.cx, top.view.cy),
    "-": () => top.zoomAbout(0.8, top.view.cx, top.view.cy) };
  if (keys[e.key]) { e.preventDefault(); keys[e.key](); }
});

// For tests and scripts: where a candidate is drawn (CSS pixels in each view), the views.
window.teach = {
  state,
  pixelOf(i) {
    const p = state.step.candidates[i];
    return top.cssOf(p[0], p[1]);
  },
  screenOf3D(i) { return view3d.ok ? view3d.screenOf(i) : null; },
  has3D: view3d.ok,
  topView() { return { ...top.view }; },
  marks() { return state.step ? marksNow() : []; },
  sizes: TOP_SIZE,
  camera() { return view3d.camera(); },
  home() { return view3d.ok ? view3d.home() : null; },
  groundUnderCamera() {
    const c = view3d.camera();
    return c && view3d.ground(c.position[0], c.position[1]);
  },
};

(async () => {
  try {
    const session = await api("/api/session");
    $("store").textContent = session.store;
    // the name this browser last labelled under comes first: a server's --labeler is a default
    $("labeler").value = localStorage.getItem("footfall-labeler") || session.labeler || "";
    await Promise.all([loadRuns(), refreshCounts()]);
    document.body.dataset.ready = "yes";
    refreshAgreement().catch(fail);
    setInterval(poll, POLL);
  } catch (e) { fail(e); }
})();
