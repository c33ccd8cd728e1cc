// texelpad lab: what both pages share. call() is the one way to the server:
// JSON in and out, a refusal's reason shown in #error (the server changed
// nothing), never thrown away: an error stays until the next request the user
// makes succeeds. {quiet: true}: a background request (a poll) that neither
// shows nor clears #error. A thrown error carries the HTTP status (e.status;
// 409: the request came too late or too early - a question answered already).
"use strict";
const $ = (id) => document.getElementById(id);

async function call(method, path, body, opts) {
  const quiet = !!(opts && opts.quiet);
  let r;
  try {
    r = await fetch(path, {method, headers: {"content-type": "application/json"},
                           body: body === undefined ? undefined : JSON.stringify(body)});
  } catch (e) {
    if (!quiet) showError("the lab server does not answer (is texelpad lab still running?)");
    throw e;
  }
  const j = await r.json().catch(() => ({error: r.statusText}));
  if (!r.ok) {
    const text = (r.status === 503 ? "board: " : "") + (j.error || r.statusText);
    if (!quiet) showError(text);
    const e = new Error(text);
    e.status = r.status;
    throw e;
  }
  if (!quiet) showError("");
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
