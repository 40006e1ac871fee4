// footfall teach: the page's requests to its server. Every failure becomes an Error with one
// line a person can act on; a server that does not answer at all is a ServerDown.

const TOKEN = new URLSearchParams(location.search).get("token");
let pending = 0;  // requests in flight that the page waits on (not the background polls)
const busyListeners = [];
const linkListeners = [];

export class ServerDown extends Error {}

export function onBusy(listener) { busyListeners.push(listener); }
export function onLink(listener) { linkListeners.push(listener); }  // (true: answering)

function busy(delta) {
  pending += delta;
  for (const listener of busyListeners) listener(pending);
}

function link(up) { for (const listener of linkListeners) listener(up); }

// A request; `quiet` ones (polls) do not show the page as busy.
export async function api(path, { quiet = false, ...options } = {}) {
  const headers = { "Content-Type": "application/json" };
  if (TOKEN) headers.Authorization = "token " + TOKEN;
  if (!quiet) busy(+1);
  try {
    let response;
    try {
      response = await fetch(path, { ...options, headers, credentials: "same-origin" });
    } catch (e) {
      link(false);
      throw new ServerDown("the teaching server is not answering: is footfall teach still " +
                           "running? Start it again and reload this page.");
    }
    link(true);
    const body = await response.json().catch(() => ({ detail: response.statusText }));
    if (!response.ok) throw new Error(body.detail || response.statusText);
    return body;
  } finally {
    if (!quiet) busy(-1);
  }
}

// A fresh id for a request that changes something: a retry sends the same one.
export function requestId() {
  const bytes = new Uint8Array(12);
  crypto.getRandomValues(bytes);
  return Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
}
