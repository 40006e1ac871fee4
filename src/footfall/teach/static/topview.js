// footfall teach: the top view of a step. World frame x forward (right on screen), y left (up
// on screen), metres. The terrain is painted once per step into an image (one pixel a
// sample); zoom (wheel, + and -) and pan (drag) only redraw that image and the marks.
import { COLOURS, NEVER_INNER, TOP_SIZE, rewardColours } from "./marks.js";

const MARGIN = 0.02;   // [m] shown around the candidate set at zoom 1
const MAX_ZOOM = 12;
const DRAG = 4;        // [CSS px] a pointer moving farther than this pans instead of clicking

export function heightRange(heights) {
  let lo = Infinity, hi = -Infinity;
  for (const row of heights) for (const h of row) if (h !== null) {
    lo = Math.min(lo, h); hi = Math.max(hi, h);
  }
  return lo <= hi ? [lo, hi] : [0, 0];
}

export class TopView {
  constructor(canvas, onPoint) {
    this.canvas = canvas;
    this.onPoint = onPoint;          // (x, y) [m]: a click on the terrain
    this.step = null;
    this.marks = [];
    this.image = null;
    this.view = { zoom: 1, cx: 0, cy: 0 };
    this.base = null;                // {cx, cy, half} [m]: the square shown at zoom 1
    this.colours = [];
    let down = null, moved = false;
    canvas.addEventListener("pointerdown", (e) => {
      down = { x: e.clientX, y: e.clientY, cx: this.view.cx, cy: this.view.cy };
      moved = false;
      canvas.setPointerCapture(e.pointerId);
    });
    canvas.addEventListener("pointermove", (e) => {
      if (!down || !this.step) return;
      const dx = e.clientX - down.x, dy = e.clientY - down.y;
      if (!moved && Math.hypot(dx, dy) <= DRAG) return;
      moved = true;
      const perPx = this.metresPerCssPixel();
      this.view.cx = down.cx - dx * perPx;
      this.view.cy = down.cy + dy * perPx;
      this.draw();
    });
    canvas.addEventListener("pointerup", (e) => {
      if (!down) return;
      const click = !moved;
      down = null;
      if (!click || !this.step) return;
      const p = this.worldOf(e.clientX, e.clientY);
      this.onPoint(p.x, p.y);
    });
    canvas.addEventListener("wheel", (e) => {
      if (!this.step) return;
      e.preventDefault();
      const p = this.worldOf(e.clientX, e.clientY);
      this.zoomAbout(e.deltaY < 0 ? 1.25 : 0.8, p.x, p.y);
    }, { passive: false });
    new ResizeObserver(() => this.draw()).observe(canvas);
  }

  // A new step: its terrain image, and the view reset to the candidate set.
  setStep(step, marks) {
    this.step = step;
    this.marks = marks;
    this.colours = rewardColours(step.rewards);
    this.image = terrainImage(step.terrain);
    const xs = step.candidates.map((p) => p[0]), ys = step.candidates.map((p) => p[1]);
    const x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
    this.base = { cx: (x0 + x1) / 2, cy: (y0 + y1) / 2,
                  half: Math.max(x1 - x0, y1 - y0) / 2 + MARGIN };
    this.reset();
  }

  setMarks(marks) { this.marks = marks; this.draw(); }

  reset() {
    if (!this.base) return;
    this.view = { zoom: 1, cx: this.base.cx, cy: this.base.cy };
    this.draw();
  }

  zoomAbout(factor, x, y) {  // keep the world point (x, y) [m] under the pointer
    const zoom = Math.min(MAX_ZOOM, Math.max(1, this.view.zoom * factor));
    const f = this.view.zoom / zoom;
    this.view = { zoom, cx: x + (this.view.cx - x) * f, cy: y + (this.view.cy - y) * f };
    this.draw();
  }

  half() { return this.base.half / this.view.zoom; }  // [m] half the side shown

  metresPerCssPixel() {
    return 2 * this.half() / this.canvas.getBoundingClientRect().width;
  }

  // CSS pixels within the canvas of the world point (x, y) [m], and the reverse.
  cssOf(x, y) {
    const rect = this.canvas.getBoundingClientRect(), h = this.half();
    return { x: (x - this.view.cx + h) / (2 * h) * rect.width,
             y: (this.view.cy + h - y) / (2 * h) * rect.height };
  }

  worldOf(clientX, clientY) {
    const rect = this.canvas.getBoundingClientRect(), h = this.half();
    return { x: this.view.cx - h + (clientX - rect.left) / rect.width * 2 * h,
             y: this.view.cy + h - (clientY - rect.top) / rect.height * 2 * h };
  }

  draw() {
    const c = this.canvas, rect = c.getBoundingClientRect(), ratio = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(rect.width * ratio)), h = Math.max(1, Math.round(rect.height * ratio));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    const g = c.getContext("2d");
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.clearRect(0, 0, w, h);
    if (!this.step || rect.width === 0) return;
    g.setTransform(ratio, 0, 0, ratio, 0, 0);  // draw in CSS pixels
    const s = this.step, t = s.terrain;
    const a = this.cssOf(t.x[0] - t.step / 2, t.y[t.y.length - 1] + t.step / 2);
    const b = this.cssOf(t.x[t.x.length - 1] + t.step / 2, t.y[0] - t.step / 2);
    g.imageSmoothingEnabled = false;
    g.drawImage(this.image, a.x, a.y, b.x - a.x, b.y - a.y);
    s.candidates.forEach((p, i) => this.dot(g, p, 3.5, this.colours[i]));
    for (const [name, leg] of Object.entries(s.robot.legs))
      this.ring(g, leg.foot, 5, name === s.robot.swing_leg ? COLOURS.swing : COLOURS.stance, 2);
    for (const m of this.marks) this.mark(g, m);
  }

  dot(g, p, r, fill) {
    const q = this.cssOf(p[0], p[1]);
    g.beginPath(); g.arc(q.x, q.y, r, 0, 2 * Math.PI);
    g.fillStyle = fill; g.fill();
  }

  ring(g, p, r, colour, width) {
    const q = this.cssOf(p[0], p[1]);
    g.beginPath(); g.arc(q.x, q.y, r, 0, 2 * Math.PI);
    g.strokeStyle = colour; g.lineWidth = width; g.stroke();
  }

  mark(g, m) {
    const p = this.step.candidates[m.index], q = this.cssOf(p[0], p[1]), r = TOP_SIZE[m.kind];
    g.lineWidth = 2.5;
    g.strokeStyle = COLOURS[m.kind];
    if (m.kind === "never_mine" || m.kind === "never_other") { this.cross(g, q, m, r); return; }
    if (m.kind === "expert") {  // a filled diamond, innermost
      g.beginPath();
      g.moveTo(q.x, q.y - r); g.lineTo(q.x + r, q.y); g.lineTo(q.x, q.y + r); g.lineTo(q.x - r, q.y);
      g.closePath(); g.fillStyle = COLOURS.expert; g.fill();
      return;
    }
    if (m.kind === "mine") { g.strokeRect(q.x - r, q.y - r, 2 * r, 2 * r); return; }
    g.beginPath(); g.arc(q.x, q.y, r, 0, 2 * Math.PI); g.stroke();
    if (m.kind === "other" && m.count > 1) {
      g.fillStyle = COLOURS.other; g.font = "bold 11px system-ui, sans-serif";
      g.fillText(String(m.count), q.x + r + 2, q.y - r);
    }
  }

  cross(g, q, m, r) {  // "never here": four arms outside every other mark, mine x, others' +
    const turn = m.kind === "never_mine" ? Math.PI / 4 : 0, width = m.kind === "never_mine" ? 3 : 2.5;
    g.beginPath();
    for (let a = 0; a < 4; a++) {
      const c = Math.cos(turn + a * Math.PI / 2), s = Math.sin(turn + a * Math.PI / 2);
      g.moveTo(q.x + NEVER_INNER * c, q.y + NEVER_INNER * s);
      g.lineTo(q.x + r * c, q.y + r * s);
    }
    g.lineCap = "round";
    g.strokeStyle = "#ffffff"; g.lineWidth = width + 2.5; g.stroke();  // a halo: seen on any ground
    g.strokeStyle = COLOURS[m.kind]; g.lineWidth = width; g.stroke();
    g.lineCap = "butt";
    if (m.kind === "never_other" && m.count > 1) {
      const x = q.x - r - 6, y = q.y - r + 6;
      g.font = "bold 11px system-ui, sans-serif"; g.lineWidth = 3; g.strokeStyle = "#ffffff";
      g.strokeText(String(m.count), x, y);
      g.fillStyle = COLOURS.never_other; g.fillText(String(m.count), x, y);
    }
  }
}

// The terrain window as an image, one pixel a sample: grey by height, red where no data.
function terrainImage(t) {
  const nx = t.x.length, ny = t.y.length, [lo, hi] = heightRange(t.heights);
  const canvas = document.createElement("canvas");
  canvas.width = nx; canvas.height = ny;
  const g = canvas.getContext("2d"), image = g.createImageData(nx, ny);
  for (let i = 0; i < nx; i++) for (let j = 0; j < ny; j++) {
    const h = t.heights[i][j], o = 4 * ((ny - 1 - j) * nx + i);
    if (h === null) { image.data.set([0xb7, 0x1c, 0x1c, 255], o); continue; }
    const v = Math.round(60 + 180 * (hi > lo ? (h - lo) / (hi - lo) : 0.5));
    image.data.set([v, v, v, 255], o);
  }
  g.putImageData(image, 0, 0);
  return canvas;
}
