// The experimenter's screen: pick a study config, a participant and start (or
// resume) a session; follow it with its parameters shown (the participant's
// screen never shows them); replay what an answer heard. The monitor polls
// quietly: an error shown (a refused start) stays until the next action.
"use strict";
const NINE = ["2sin", "3sin", "4sin", "white", "pink", "blue", "square", "triangle", "sawtooth"];
let configs = {}, current = null, strip = null, poll = null;

function fmt(v) {
  if (typeof v === "number") return Number.isInteger(v) ? String(v) : v.toFixed(3);
  if (v && typeof v === "object" && "pitch_db" in v && "irregularity_db" in v
      && Object.keys(v).length <= 3)
    return fmt(v.pitch_db) + " dB pitch, " + fmt(v.irregularity_db) + " dB irregularity";
  return JSON.stringify(v);
}

function configChanged() {
  const c = configs[$("config").value] || {};
  $("config-title").textContent = c.error ? "cannot be used: " + c.error : (c.title || "");
  $("start").disabled = !!c.error;
  $("reference-box").hidden = !(c.protocol === "pursuit" || c.protocol === "search");
  if (c.reference) $("reference").value = c.reference.name;
  $("matches-box").hidden = c.protocol !== "quant" && c.protocol !== "evaluate";
}

async function loadSessions() {
  const res = await call("GET", "/api/sessions");
  const body = $("sessions").querySelector("tbody");
  body.innerHTML = "";
  const frees = [];
  for (const s of res.sessions.slice().reverse()) {
    const tr = el("tr", {});
    tr.appendChild(el("td", {}, s.id));
    tr.appendChild(el("td", {}, s.protocol || s.error));
    tr.appendChild(el("td", {}, s.config_file || ""));
    tr.appendChild(el("td", {}, s.error ? "" : s.answers + (s.finished ? " (finished)" : "")));
    const td = el("td", {});
    td.appendChild(el("button", {onclick: () => follow(s.id)}, "follow"));
    tr.appendChild(td);
    const td2 = el("td", {});
    td2.appendChild(el("a", {href: "/participant?s=" + s.id, target: "_blank"},
                       s.finished ? "" : "participant screen"));
    tr.appendChild(td2);
    body.appendChild(tr);
    // matches for a quantization test or a similarity matrix: a free
    // exploration's, a finished guided exploration's or search's end point
    if (s.protocol === "free" || (s.finished && (s.protocol === "pursuit" ||
                                                 s.protocol === "search"))) frees.push(s);
  }
  const m = $("matches"), keep = [...m.selectedOptions].map((o) => o.value);
  m.innerHTML = "";
  frees.forEach((s) => m.appendChild(el("option", {value: s.id}, s.id)));
  [...m.options].forEach((o) => { o.selected = keep.includes(o.value); });
}

async function follow(id) {
  current = id;
  $("monitor-box").hidden = false;
  $("participant-link").href = "/participant?s=" + id;
  $("participant-link").textContent = location.origin + "/participant?s=" + id;
  clearInterval(poll);
  await refresh();
  poll = setInterval(refresh, 1000);
}

async function refresh() {
  if (!current) return;
  let m;
  try { m = await call("GET", "/api/sessions/" + current + "/monitor", undefined, {quiet: true}); }
  catch (e) { return; }
  $("monitor-title").textContent = current + ": " + m.title;
  const box = $("monitor");
  box.innerHTML = "";
  const rows = [["answers", m.question.done ? m.answers_so_far + " (finished)" : m.answers_so_far],
                ["seed", m.seed], ["file", m.file]];
  if (m.protocol === "free" && m.sliders) rows.push(["sliders", fmt({pitch_db: m.sliders[0],
                                                                     irregularity_db: m.sliders[1]})]);
  for (const [k, v] of Object.entries(m.detail)) rows.push([k, v]);
  rows.push(["playing", m.playing === null ? "-" : m.question.options
             ? m.question.options[m.playing] || m.playing : m.playing]);
  const t = el("table", {id: "detail"});
  for (const [k, v] of rows) {
    const tr = el("tr", {});
    tr.appendChild(el("th", {}, k));
    tr.appendChild(el("td", {}, typeof v === "string" ? v : fmt(v)));
    t.appendChild(tr);
  }
  box.appendChild(t);
  if (strip) strip.refresh();
}

$("config").onchange = configChanged;
$("start").onclick = async () => {
  const body = {config: $("config").value, participant: $("participant").value.trim()};
  const seed = $("seed").value.trim();
  if (seed) {                   // a whole number, or nothing (random): never a silent guess
    if (!/^[0-9]{1,10}$/.test(seed) || Number(seed) >= 2 ** 31) {
      showError("not started: seed " + JSON.stringify(seed) + " is not a whole number in " +
                "0 .. 2147483647 (leave it empty for a random seed)");
      return;
    }
    body.seed = Number(seed);
  }
  const c = configs[$("config").value];
  if (!$("reference-box").hidden && (!c.reference || c.reference.name !== $("reference").value))
    body.reference = {kind: "reference", name: $("reference").value};
  const picked = [...$("matches").selectedOptions].map((o) => o.value);
  if (!$("matches-box").hidden && picked.length) body.matches_from = picked;
  let res;
  try { res = await call("POST", "/api/sessions", body); }
  catch (e) { showError("not started: " + e.message); return; }
  await loadSessions();
  await follow(res.id);
};
$("release").onclick = async () => {
  const r = await call("POST", "/api/board/release", {});
  $("released").textContent = r.released ? "released the board from " + r.released
                                         : "no session held the board";
};
$("replay").onclick = async () => {
  if (current) await call("POST", "/api/sessions/" + current + "/replay",
                          {record: Number($("replay-n").value)});
  refresh();
};

(async () => {
  NINE.forEach((n) => $("reference").appendChild(el("option", {value: n}, n)));
  strip = await boardLine(true);
  const res = await call("GET", "/api/configs");
  configs = res.configs;
  for (const [name, c] of Object.entries(configs)) {
    $("config").appendChild(el("option", {value: name}, name + (c.error ? " (broken)" : "")));
  }
  configChanged();
  await loadSessions();
})();
