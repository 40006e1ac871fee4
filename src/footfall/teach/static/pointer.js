// footfall teach: the candidate of F under the mouse pointer, in whichever view it is over (the
// top view or the 3D view), within the distance a click on the terrain snaps to a candidate.
// World frame x forward, y left, metres.

const SNAP = 0.03;  // [m] the snapping distance when a step does not give its own (snap_m)

// Index of the candidate (n, 3) [m] horizontally nearest (x, y) [m], or null when none lies
// within `radius` [m].
export function nearestCandidate(candidates, x, y, radius) {
  let best = null, d = Infinity;
  candidates.forEach((p, i) => {
    const e = Math.hypot(p[0] - x, p[1] - y);
    if (e < d) { d = e; best = i; }
  });
  return d <= radius ? best : null;
}

export class Pointer {
  // topCanvas, box3d: the views' elements; top: the TopView; view3d: the 3D view (its pick).
  constructor(topCanvas, box3d, top, view3d) {
    this.top = top;
    this.view3d = view3d;
    this.where = null;  // {view: "top" | "3d", x, y [client CSS px]}; null: over neither view
    for (const [element, view] of [[topCanvas, "top"], [box3d, "3d"]]) {
      element.addEventListener("pointermove", (e) => {
        this.where = { view, x: e.clientX, y: e.clientY };
      });
      element.addEventListener("pointerleave", () => {
        if (this.where && this.where.view === view) this.where = null;
      });
    }
  }

  // The index in `step`'s F of the candidate under the pointer, or null.
  candidate(step) {
    const w = this.where;
    if (!w || !step) return null;
    const radius = step.snap_m ?? SNAP;
    if (w.view === "top") {
      const p = this.top.worldOf(w.x, w.y);
      return nearestCandidate(step.candidates, p.x, p.y, radius);
    }
    const hit = this.view3d.pick(w.x, w.y);
    if (!hit) return null;
    if (hit.candidate !== undefined) return hit.candidate;
    return nearestCandidate(step.candidates, hit.point[0], hit.point[1], radius);
  }
}
