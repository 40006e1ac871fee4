// footfall teach: the runs list. A refresh updates the rows in place (a row replaced under the
// pointer between a press and its release would swallow the click), adding rows for new runs.

const WIDE = [1, 2, 3, 7]; // the columns left out beside an open run (key, board, reward,
                           // labels: in each row's tooltip)

// The table body `body` filled with `runs` (GET /api/runs); `name`: whose labels count as mine;
// onOpen(run id): a row clicked.
export function fillRuns(body, runs, name, onOpen) {
  const rows = new Map([...body.children].map((tr) => [Number(tr.dataset.run), tr]));
  for (const r of runs) {
    let tr = rows.get(r.id);
    if (!tr) {
      tr = document.createElement("tr");
      tr.dataset.run = r.id;
      for (let i = 0; i < 9; i++) {
        const td = document.createElement("td");
        if (i >= 1 && i <= 4) td.className = "text";
        if (WIDE.includes(i)) td.classList.add("wide");
        tr.append(td);
      }
      tr.addEventListener("click", () => onOpen(r.id));
      body.append(tr);
    }
    rows.delete(r.id);
    const mine = (r.labelled_by || {})[name] || 0;
    const cells = [r.id, r.key ?? "", r.board, r.chooser, r.success ? "crossed" : r.failure,
      r.slip_mean_mm == null ? "-" : r.slip_mean_mm.toFixed(1), r.steps, r.labels,
      name ? `${mine} / ${r.steps}` : "-"];
    tr.title = `${r.key ?? ""} · ${r.board} · ${r.chooser}`;
    cells.forEach((c, i) => {
      const td = tr.children[i];
      if (td.textContent !== String(c)) td.textContent = c;
      if (i === 4) {
        td.classList.toggle("fail", !r.success);
        td.title = !r.success && r.reason && r.reason !== r.failure ?
          `the run ended: ${r.reason}` : "";
      }
    });
  }
  for (const gone of rows.values()) gone.remove();  // (a store's runs are never removed)
}
