// texelpad lab: what both pages share. call() is the one way to the server:
// JSON in and out, a refusal's reason shown in #error (the server changed
// nothing), never thrown away.
"use strict";
const $ = (id) => document.getElementById(id);

async function call(method, path, body) {
  let r;
  try {
    r = await fetch(path, {method, headers: {"content-type": "application/json"},
                           body: body === undefined ? undefined : JSON.stringify(body)});
  } catch (e) {
    showError("the lab server does not answer (is texelpad lab still running?)");
    throw e;
  }
  const j = await r.json().catch(() => ({error: r.statusText}));
  if (!r.ok) {
    showError((r.status === 503 ? "board: " : "") + (j.error || r.statusText));
    throw new Error(j.error || r.statusText);
  }
  showError("");
  return j;
}

function showError(text) {
  const e = $("error");
  if (e) e.textContent = text;
}

function el(tag, attrs, text) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === "onclick" || k === "oninput" || k === "onchange") e[k] = v;
    else e.setAttribute(k, v);
  }
  if (text !== undefined) e.textContent = text;
  return e;
}

// the board line and, when the board is the virtual one (or ?strip=1), the
// strip: see and hear the playing scene (strip.js)
async function boardLine(showStrip, stripOptions) {
  let st;
  try { st = await call("GET", "/api/status"); } catch (e) { return null; }
  $("status").textContent = "board " + (st.board || "?") + (st.running ? " playing" : " stopped");
  const want = showStrip || new URLSearchParams(location.search).get("strip") === "1"
               || st.board === "virtual";
  if (want && window.texelpadStrip && $("strip")) {
    $("strip-box").hidden = false;
    return window.texelpadStrip($("strip"), stripOptions || {});
  }
  return null;
}
