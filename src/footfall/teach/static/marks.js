// footfall teach: what is marked on a step's candidates, and in which colours. One list of
// marks per step, drawn by both views: each kind has its own colour and shape, and the shapes
// nest (the outermost first), so that marks on one candidate never hide each other. A "never
// here" mark is a cross around everything else: mine a dark x, others' a grey + with their
// number; the two point different ways, so that both show on one candidate.

export const COLOURS = {
  chosen: "#e53935",   // the robot's choice: a red ring
  expert: "#2e7d32",   // the synthetic expert's best: a green diamond (innermost)
  mine: "#1565c0",     // my label: a blue square
  other: "#8e24aa",    // others' labels: a purple ring, with their number
  never_mine: "#212121",   // my "never here": a dark x, outermost
  never_other: "#616161",  // others' "never here": a grey +, outermost, with their number
  stance: "#263238",   // stance feet: dark rings
  swing: "#00897b",    // the swing foot: a teal ring
};

// Candidate colours by the robot's reward: low blue, mid grey, high yellow; invalid grey.
const LOW = [0x3b, 0x4c, 0xc0], MID = [0xdd, 0xdd, 0xdd], HIGH = [0xf7, 0xd1, 0x3d];

function mix(a, b, t) { return a.map((v, i) => Math.round(v + (b[i] - v) * t)); }

export function rewardColours(rewards) {
  const finite = rewards.filter((r) => r !== null);
  const lo = Math.min(...finite), hi = Math.max(...finite);
  return rewards.map((r) => {
    if (r === null) return "#9e9e9e";
    const t = hi > lo ? (r - lo) / (hi - lo) : 1;
    const c = t < 0.5 ? mix(LOW, MID, 2 * t) : mix(MID, HIGH, 2 * t - 1);
    return "#" + c.map((v) => v.toString(16).padStart(2, "0")).join("");
  });
}

// The order of the kinds, outermost first (each nests inside the one before on a candidate).
export const ORDER = ["never_other", "never_mine", "other", "mine", "chosen", "expert"];

// The "never here" marks of a step: mine, and others' counted per candidate.
function neverMarks(step, me) {
  const marks = [], others = new Map();
  for (const m of step.marks || []) {
    if (m.labeler === me) {
      marks.push({ index: m.candidate, kind: "never_mine", count: 1, names: [me] });
      continue;
    }
    const names = others.get(m.candidate) || [];
    names.push(m.labeler);
    others.set(m.candidate, names);
  }
  for (const [index, names] of others)
    marks.push({ index, kind: "never_other", count: names.length, names });
  return marks;
}

// The marks of a step: [{index, kind, count, names}], outermost kind first on each candidate.
// expertBest: the expert's best index, or null while the run is being judged.
export function stepMarks(step, expertBest, me) {
  const marks = neverMarks(step, me);
  const others = new Map();
  for (const l of step.labels) {
    const index = l.chosen;
    if (l.labeler === me) {
      if (l.verdict === "foothold") marks.push({ index, kind: "mine", count: 1, names: [me] });
      continue;
    }
    if (l.verdict !== "foothold") continue;
    const names = others.get(index) || [];
    names.push(l.labeler);
    others.set(index, names);
  }
  for (const [index, names] of others)
    marks.push({ index, kind: "other", count: names.length, names });
  marks.push({ index: step.chosen, kind: "chosen", count: 1, names: [] });
  if (expertBest !== null && expertBest !== undefined)
    marks.push({ index: expertBest, kind: "expert", count: 1, names: [] });
  return marks.sort((a, b) => ORDER.indexOf(a.kind) - ORDER.indexOf(b.kind));
}

// Sizes [CSS px] of the nested top-view shapes: outermost to innermost (a cross's arms reach
// from NEVER_INNER out to its size: outside every ring and square).
export const TOP_SIZE = { never_other: 24, never_mine: 23, other: 13, mine: 10, chosen: 7,
                          expert: 4.5 };
export const NEVER_INNER = 15;
