// footfall teach: the counts and agreement figures as the page words them (the same words as
// `footfall demos info`: footfall.teach.agreement.agreement_lines).

function pct(t) { return t.share === null ? "-" : `${Math.round(100 * t.share)} %`; }

export function countsText(c) {
  const names = Object.entries(c.labels.by_labeler)
    .map(([n, v]) => `${n}: ${v.foothold} foothold${v.foothold === 1 ? "" : "s"}, ` +
      `${v.fine} fine`).join("; ");
  const never = Object.entries(c.marks || {}).map(([n, v]) => `${n}: ${v}`).join("; ");
  return `labels: ${names || "none yet"}` +
    (c.labels.disagreements ? `; labelers disagree on ${c.labels.disagreements} ` +
      `step${c.labels.disagreements === 1 ? "" : "s"}` : "") +
    (never ? ` · "never here" marks: ${never}` : "");
}

export function agreementText(a) {
  const lines = Object.entries(a.with_expert).map(([n, t]) =>
    `${n} agrees with the synthetic expert on ${t.agree} of ${t.steps} steps (${pct(t)})`);
  for (const [pair, t] of Object.entries(a.between))
    lines.push(`${pair} agree on ${t.agree} of ${t.steps} steps (${pct(t)})`);
  const marks = a.marks || { with_expert: {}, between: {} };
  for (const [n, t] of Object.entries(marks.with_expert))
    lines.push(`${n}'s 'never here' marks: the synthetic expert also refuses ${t.refused} of ` +
      `${t.marks} (${pct(t)})`);
  for (const [pair, t] of Object.entries(marks.between))
    lines.push(`${pair} mark the same candidates: ${t.shared} of ${t.marks} marks on ` +
      `${t.steps} steps (${pct(t)})`);
  return lines.length ? lines.join("\n") : "no labels yet";
}
