// texelpad lab's scene editor (editor.html; the API and the overlap rule:
// host/texelpad/web/editor.py). A plain script on lab.js (call, $, el) and
// strip.js (texelpadStrip with onSelect: a drag selects a span).
//
// The page holds the scene in the editor's form - the regions as the server
// last answered them, sorted, each with its texture (a brush by its file or
// design) and a label. Every change sends the whole scene with the new region
// last (painting order: it wins where it overlaps) or one region less; the
// server resolves, pushes, and answers the scene the board now plays and its
// strip, which the page adopts. Undo sends the scene before the last change
// (the history is here, in the page); "base" (the scene_id the page edited)
// makes the server refuse when another page changed the board's scene since.
"use strict";

const editor = {palette: null, regions: [], sceneId: null, history: [], strip: null,
                busy: false, selected: null, lastMs: null};
window.editor = editor;             // (the tests and the curious)

const HISTORY_MAX = 50;

function num(id) {
  const v = Number($(id).value);
  if ($(id).value === "" || !Number.isFinite(v)) throw new Error(id + ": enter a number");
  return v;
}

function seedOf(id) {
  const v = num(id);
  if (!Number.isInteger(v) || v < 0 || v > 4294967295) {
    throw new Error(id + ": a seed is a whole number 0 .. 4294967295");
  }
  return v;
}

// the texture the form describes, in the editor's form (editor.py)
function texture() {
  const kind = $("kind").value;
  if (kind === "brush") {
    const src = document.querySelector("input[name=brush-source]:checked").value;
    const seed = seedOf("brush-seed");
    if (src === "file") {
      if (!$("brush-file").value) throw new Error("no brush file chosen (the folder is empty?)");
      return {kind: "brush", file: $("brush-file").value, seed};
    }
    return {kind: "brush", design: design(), seed};
  }
  if (kind === "texel") {
    const dx = editor.palette.display.dx_um / 1000;
    return {kind: "texel", pitch_db: num("pitch"), irregularity_db: num("irreg"),
            texel_samples: Math.max(1, Math.round(num("texel-mm") / dx)),
            seed: seedOf("texel-seed")};
  }
  if (kind === "reference") return {kind: "reference", name: $("reference").value};
  if (kind === "constant") return {kind: "constant", level: num("const-level")};
  // a kind the palette describes (its module's FIELDS: texel/runtime/kinds/)
  const t = {kind};
  for (const f of editor.palette.forms[kind]) {
    const id = "g-" + kind + "-" + f.key;
    t[f.key] = f.type === "word" ? $(id).value : num(id);
  }
  return t;
}

// a form for each kind the palette describes by its fields, built from them
function addForms(forms) {
  for (const [kind, fields] of Object.entries(forms)) {
    $("kind").appendChild(el("option", {value: kind}, "a " + kind));
    const fs = el("fieldset", {id: "f-" + kind, hidden: ""});
    fs.appendChild(el("legend", {}, kind));
    for (const f of fields) {
      const id = "g-" + kind + "-" + f.key;
      let input;
      if (f.type === "word") {
        input = el("select", {id});
        for (const w of f.words) input.appendChild(el("option", {value: w}, w));
      } else {
        input = el("input", {id, type: "number", min: f.min, max: f.max,
                             step: f.type === "int" ? 1 : "any"});
      }
      input.value = f.default;
      const lab = el("label", {}, f.label + " ");
      lab.appendChild(input);
      fs.appendChild(lab);
    }
    $("f-constant").after(fs);
  }
}

function design() {
  return {shape: $("shape").value, level: num("level"), mean: num("mean"), k: num("k")};
}

function span() {
  const s = num("start"), e = num("end");
  if (!(e > s)) throw new Error("select a span: drag on the strip (to must be after from)");
  return [s, e];
}

// the regions as the server takes them back (no labels)
function bare(regions) {
  return regions.map((r) => ({start_mm: r.start_mm, end_mm: r.end_mm, texture: r.texture}));
}

// an answer of GET or POST /api/editor/scene: what the board plays now
function adopt(a) {
  editor.regions = a.regions;
  editor.sceneId = a.scene_id;
  editor.strip.show(a.strip);
  if (document.activeElement !== $("name")) $("name").value = a.name || "";
  table();
}

// send the whole scene; `record`: the scene before goes on the undo history
async function push(regions, what, record = true) {
  if (editor.busy) return false;
  editor.busy = true;
  const before = editor.regions;
  const body = {regions: bare(regions), base: editor.sceneId};
  const name = $("name").value.trim();
  if (name) body.name = name;
  const t0 = performance.now();
  try {
    const a = await call("POST", "/api/editor/scene", body);
    editor.lastMs = performance.now() - t0;
    if (record) {
      editor.history.push(before);
      if (editor.history.length > HISTORY_MAX) editor.history.shift();
    }
    adopt(a);
    $("info").textContent = what + ": " + a.regions.length + " region(s) playing ("
      + Math.round(editor.lastMs) + " ms to the board and back)";
    return true;
  } catch (e) {
    $("info").textContent = "";
    return false;
  } finally {
    editor.busy = false;
    $("undo").disabled = editor.history.length === 0;
    document.body.dataset.pushes = String(Number(document.body.dataset.pushes || 0) + 1);
  }
}

function guarded(fn) {
  return () => {
    try { return fn(); } catch (e) { showError(e.message); return null; }
  };
}

const paint = guarded(() => {
  const [s, e] = span();
  const tex = texture();
  return push(editor.regions.concat([{start_mm: s, end_mm: e, texture: tex}]), "painted");
});

function removeRegion(i) {
  return push(editor.regions.filter((_, j) => j !== i), "removed region " + (i + 1));
}

async function undo() {
  if (!editor.history.length) return;
  const prev = editor.history[editor.history.length - 1];
  if (await push(prev, "undone", false)) editor.history.pop();
  $("undo").disabled = editor.history.length === 0;
}

// --- the region list ------------------------------------------------------------------
function table() {
  const tb = $("regions").querySelector("tbody");
  tb.textContent = "";
  if (!editor.regions.length) {
    const tr = el("tr");
    tr.appendChild(el("td", {colspan: "5", class: "muted"},
                      "no region: the board plays its idle level everywhere"));
    tb.appendChild(tr);
    return;
  }
  const sel = editor.strip.selection;
  editor.regions.forEach((r, i) => {
    const tr = el("tr");
    if (sel && Math.abs(sel.start_mm - r.start_mm) < 0.006 && Math.abs(sel.end_mm - r.end_mm) < 0.006) {
      tr.className = "selected";
    }
    tr.appendChild(el("td", {}, String(i + 1)));
    tr.appendChild(el("td", {}, r.start_mm.toFixed(2)));
    tr.appendChild(el("td", {}, r.end_mm.toFixed(2)));
    tr.appendChild(el("td", {class: "what"}, r.label));
    const td = el("td");
    td.appendChild(el("button", {type: "button", onclick: () => selectSpan(r.start_mm, r.end_mm)},
                      "select"));
    td.appendChild(el("button", {type: "button", class: "remove",
                                 onclick: () => removeRegion(i)}, "remove"));
    tr.appendChild(td);
    tb.appendChild(tr);
  });
}

function selectSpan(s, e) {
  editor.strip.select(s, e);
  $("start").value = s.toFixed(4).replace(/\.?0+$/, "");
  $("end").value = e.toFixed(4).replace(/\.?0+$/, "");
  table();
}

// --- the form ---------------------------------------------------------------------------
function showKind() {
  for (const o of $("kind").options) {
    $("f-" + o.value).hidden = $("kind").value !== o.value;
  }
}

function showSource() {
  const src = document.querySelector("input[name=brush-source]:checked").value;
  $("design-row").style.opacity = src === "design" ? "1" : "0.45";
}

function fillBrushes(list) {
  const sel = $("brush-file"), was = sel.value;
  sel.textContent = "";
  for (const b of list) {
    const o = el("option", {value: b.file}, b.error ? b.file + " (broken: " + b.error + ")"
                 : b.file + (b.name && b.name !== b.file.replace(/\.[a-z]+$/, "") ? " - " + b.name : ""));
    if (b.error) o.disabled = true;
    sel.appendChild(o);
  }
  if (!list.length) sel.appendChild(el("option", {value: ""}, "(no brush files yet)"));
  if (was && list.some((b) => b.file === was)) sel.value = was;
}

async function saveBrush() {
  let body;
  try {
    body = {name: $("save-name").value.trim(), design: design()};
  } catch (e) {
    showError(e.message);
    return;
  }
  if ($("save-replace").checked) body.replace = true;
  let a;
  try {
    a = await call("POST", "/api/editor/brushes", body);   // (a refusal is shown by call)
  } catch (e) {
    return;
  }
  fillBrushes(a.brushes);
  $("brush-file").value = a.saved;
  $("info").textContent = "saved " + a.saved + " in the brush folder";
}

function setLimits(p) {
  const lim = (id, spec) => { $(id).min = spec.min; $(id).max = spec.max; };
  lim("level", p.design.level); lim("mean", p.design.mean); lim("k", p.design.k);
  $("level").value = p.design.level.default;
  $("mean").value = p.design.mean.default;
  $("k").value = p.design.k.default;
  lim("pitch", p.texel.pitch_db); lim("irreg", p.texel.irregularity_db);
  const dx = p.display.dx_um / 1000;
  $("texel-mm").min = dx; $("texel-mm").step = dx;
  $("texel-mm").value = (p.texel.texel_samples.default * dx).toFixed(4);
  $("start").max = $("end").max = p.display.length_mm;
}

async function main() {
  editor.strip = window.texelpadStrip($("strip"), {
    path: "/api/editor/strip", autoRefresh: false, muteButton: $("mute"),
    onSelect: (s, e) => selectSpan(s, e),
    onChange: (s) => { if (s.error) showError(s.error); }});
  const mode = () => {
    $("mode").textContent = editor.strip.mode === "select" ? "drag: select a span"
                                                           : "drag: feel (finger and sound)";
    $("strip").className = editor.strip.mode === "select" ? "" : "feel";
  };
  $("mode").onclick = () => {
    editor.strip.setMode(editor.strip.mode === "select" ? "feel" : "select");
    mode();
  };
  mode();
  $("kind").onchange = showKind;
  document.querySelectorAll("input[name=brush-source]").forEach((r) => { r.onchange = showSource; });
  $("brush-file").onchange = () => {
    document.querySelector("input[name=brush-source][value=file]").checked = true;
    showSource();
  };
  ["shape", "level", "mean", "k"].forEach((id) => $(id).addEventListener("input", () => {
    document.querySelector("input[name=brush-source][value=design]").checked = true;
    showSource();
  }));
  document.querySelectorAll(".reseed").forEach((b) => {
    b.onclick = () => { $(b.dataset.for).value = Math.floor(Math.random() * 1e6); };
  });
  $("const-level").oninput = () => { $("const-out").textContent = Number($("const-level").value).toFixed(2); };
  const typed = () => {
    const s = Number($("start").value), e = Number($("end").value);
    if ($("start").value !== "" && $("end").value !== "" && e > s) editor.strip.select(s, e);
    else editor.strip.select(null);
    table();
  };
  $("start").oninput = typed;
  $("end").oninput = typed;
  $("whole").onclick = () => selectSpan(0, editor.palette.display.length_mm);
  $("paint").onclick = paint;
  $("undo").onclick = undo;
  $("undo").disabled = true;
  $("clear").onclick = () => push([], "cleared");
  $("repush").onclick = () => push(editor.regions, "played again");
  $("save").onclick = saveBrush;
  showKind();
  showSource();

  let st;
  try {
    st = await call("GET", "/api/status");
    editor.palette = await call("GET", "/api/editor/palette");
  } catch (e) {
    $("status").textContent = "no board";
    return;
  }
  const p = editor.palette;
  $("status").textContent = "board " + (st.board || "?") + ": " + p.display.positions
    + " positions of " + p.display.dx_um + " um (" + p.display.length_mm + " mm)";
  for (const name of Object.keys(p.shapes)) $("shape").appendChild(el("option", {value: name}, name));
  $("shape").value = "pink";
  for (const name of p.references) $("reference").appendChild(el("option", {value: name}, name));
  addForms(p.forms);
  fillBrushes(p.brushes);
  $("folder").textContent = "(in " + p.brush_folder + ")";
  setLimits(p);
  adopt(await call("GET", "/api/editor/scene"));
  document.body.dataset.ready = "1";
}

main();
