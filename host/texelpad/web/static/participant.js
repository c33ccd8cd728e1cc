// The participant's screen: only what a participant may see - option labels,
// the answers, a slider's position - never a parameter value (the server
// sends none). ?s=PARTICIPANT/SESSION names the session; reloading the page
// (or a crashed server coming back) resumes where it stopped.
//
// One click, one answer: every request names the question it is for
// (question.number); while one is in flight the buttons are disabled, and a
// request the server refuses as too late (409: answered already, or the
// board played something else since) reloads the question as it is now.
"use strict";
const sid = new URLSearchParams(location.search).get("s");
let strip = null, timer = null, number = null, busy = false;

// every button and slider of the question, disabled while a request is in flight
function setBusy(v) {
  busy = v;
  document.querySelectorAll("#question button, #question input").forEach((b) => {
    b.disabled = v;
  });
}

// a 409: the page is behind (or ahead of) the session; show it as it is now
async function reload(e) {
  if (!e || e.status !== 409) return false;
  show(await call("GET", "/api/sessions/" + sid));
  showError(/does not play|not what plays/.test(e.message)
            ? "The texture changed: feel it again, then answer." : "");
  return true;
}

const PROMPTS = {
  pair: "Feel A and B. Which one is closer to the reference on the left half?",
  three: "Feel the three textures. Which one is different from the other two?",
  pick: "Feel the three candidates. Which one is closest to the reference on the left half?",
  sliders: "Move the sliders until the right half feels like the left half.",
  rate: "How similar do the left and right halves feel?"};

function label(kind, a, q) {
  if (kind === "pair") return a === "unsure" ? "unsure" : a + " is closer";
  if (kind === "three") return q.options[a] + " is different";
  if (kind === "rate") return String(a);
  const [k, v] = Object.entries(a)[0];
  if (k === "stop") return "I am satisfied: stop";
  return (k === "choose" ? "closest: " : "save ") + q.options[v];
}

function markPlaying(k) {
  [...$("feel").children].forEach((c, i) => c.classList.toggle("playing", i === k));
  if (strip) strip.refresh();
}

async function answer(a) {
  let res;
  try {
    res = await call("POST", "/api/sessions/" + sid + "/answer", {answer: a, question: number});
  } catch (e) {
    setBusy(false);
    if (!(await reload(e))) throw e;
    return;
  }
  show(res);
  if (res.board_lost)           // the answer is kept; the next question plays when it is back
    showError("Your answer is saved, but the board is gone (" + res.board_lost +
              "). Reload this page when it is back.");
}

// the search's friction slider (seed 003): the level of all three candidates; a feel
// carries it, and so does a choose or save (the server checks it is what plays)
let level = null, playingOption = 0;
function withLevel(a) {
  return (level === null || "stop" in a) ? a : Object.assign({}, a, {level: level});
}

async function feel(k) {
  if (busy) return;
  setBusy(true);
  try {
    const body = {option: k, question: number};
    if (level !== null) body.level = level;
    const r = await call("POST", "/api/sessions/" + sid + "/feel", body);
    playingOption = r.playing;
    markPlaying(r.playing);
  } catch (e) {
    setBusy(false);
    if (!(await reload(e))) throw e;
    return;
  }
  setBusy(false);
}

// free exploration: slider changes go to the board one at a time, the latest wins;
// sliderFailed: the last one did not reach the board (the server answers only
// the match that plays), so "this is my match" sends it again first
let sliderBusy = false, sliderNext = null, sliderRange = null, sliderFailed = false;
// the irregularity slider: linear in dB, or (the lab's app) linear in sigma
// (decades), sent as 10 log10(max(sigma, 0.001)) dB (study/free.py)
function irregOf(x) {
  const r = sliderRange;
  if (r.irregularity_scale !== "sigma") {
    const [s0, s1] = r.irregularity_db;
    return Math.round((s0 + (s1 - s0) * x / 1000) * 1000) / 1000;
  }
  const sigma = r.sigma[0] + (r.sigma[1] - r.sigma[0]) * x / 1000;
  return Math.round(10000 * Math.log10(Math.max(sigma, 0.001))) / 1000;
}
function positionOf(db) {
  const r = sliderRange;
  if (r.irregularity_scale !== "sigma") {
    const [s0, s1] = r.irregularity_db;
    return Math.round(1000 * (db - s0) / (s1 - s0));
  }
  return Math.round(1000 * (Math.pow(10, db / 10) - r.sigma[0]) / (r.sigma[1] - r.sigma[0]));
}
// seed 001's mapping: two plain sliders (0 .. 100 in `step`s; study/mapping.py)
function plainOf(x) {
  const [lo, hi] = sliderRange.pitch, step = sliderRange.step;
  return Math.min(hi, Math.round((lo + (hi - lo) * x / 1000) / step) * step);
}
function sliderValues() {
  if (sliderRange.pitch)
    return {pitch: plainOf(Number($("pitch").value)),
            irregularity: plainOf(Number($("irregularity").value))};
  const [p0, p1] = sliderRange.pitch_db;
  return {pitch_db: Math.round((p0 + (p1 - p0) * $("pitch").value / 1000) * 1000) / 1000,
          irregularity_db: irregOf(Number($("irregularity").value))};
}
async function slide() {
  sliderNext = sliderValues();
  if (sliderBusy) return;
  sliderBusy = true;
  try {
    while (sliderNext) {
      const v = sliderNext; sliderNext = null;
      sliderFailed = true;              // until the board says it plays v
      await call("POST", "/api/sessions/" + sid + "/feel", Object.assign({question: number}, v));
      sliderFailed = false;
      if (strip) strip.refresh();
    }
  } finally { sliderBusy = false; }
}

function show(res) {
  const q = res.question;
  number = q.number;
  setBusy(false);               // (the request that brought it is done)
  clearInterval(timer); $("timer").textContent = "";
  if (q.done) {
    $("question").hidden = true; $("done").hidden = false;
    $("progress").textContent = "";
    if (strip) strip.refresh();
    return;
  }
  $("question").hidden = false; $("done").hidden = true;
  const lo = q.slider ? q.slider.range[0] : (q.answers || [])[0];
  const hi = q.slider ? q.slider.range[1] : (q.answers || [])[(q.answers || []).length - 1];
  $("prompt").textContent = q.adjective     // seed 003's Phase 2: one adjective at a time
    ? "Feel the texture. Rate its " + q.adjective + " (" + lo + " = " + q.anchors[0] + ", " +
      hi + " = " + q.anchors[1] + ")."
    : q.step === "similarity"
    ? "Feel the real texture and the virtual one (one at a time, on the whole display). How " +
      "similar do they feel? (" + lo + " = completely different, " + hi +
      " = completely the same)"
    : (q.kind === "pair" && q.presentation === "whole")
    ? "Feel the reference, A and B (one at a time, on the whole display). Which of A and B is " +
      "closer to the reference?"
    : q.kind === "rate"
    ? (q.presentation === "whole" ? "Feel the reference and the rendering (one at a time, on " +
       "the whole display). How similar do they feel?" : PROMPTS.rate) + " (" + (q.slider ? q.slider.range[0] : q.answers[0]) +
      " = completely different, " +
      (q.slider ? q.slider.range[1] : q.answers[q.answers.length - 1]) + " = identical)"
    : PROMPTS[q.kind] || "";
  $("feel").innerHTML = ""; $("answers").innerHTML = "";
  $("sliders").hidden = q.kind !== "sliders";
  q.options.forEach((name, k) => {
    $("feel").appendChild(el("button", {id: "feel-" + k, onclick: () => feel(k)},
                             "feel " + name));
  });
  playingOption = res.playing;        // (null: nothing of this session plays)
  markPlaying(res.playing);
  if (q.kind === "sliders") {
    sliderRange = q.sliders;
    const [p, s] = res.sliders || q.start;
    if (q.sliders.pitch) {              // plain sliders (the mapping)
      const [lo, hi] = q.sliders.pitch;
      $("pitch").value = Math.round(1000 * (p - lo) / (hi - lo));
      $("irregularity").value = Math.round(1000 * (s - lo) / (hi - lo));
    } else {
      const [p0, p1] = q.sliders.pitch_db;
      $("pitch").value = Math.round(1000 * (p - p0) / (p1 - p0));
      $("irregularity").value = positionOf(s);
    }
    $("pitch").oninput = slide; $("irregularity").oninput = slide;
    const box = $("confidence");
    box.hidden = !q.confidence;
    box.querySelectorAll("label").forEach((l) => l.remove());
    const confSlider = q.confidence && q.confidence_input === "slider";
    if (confSlider) {                   // the lab's app: a continuous slider from the middle
      const l = el("label", {});
      l.appendChild(document.createTextNode(q.confidence[0] + " "));
      l.appendChild(el("input", {type: "range", id: "confidence-slider", min: q.confidence[0],
                                 max: q.confidence[1], step: "0.01",
                                 value: String((q.confidence[0] + q.confidence[1]) / 2)}));
      l.appendChild(document.createTextNode(" " + q.confidence[1]));
      box.appendChild(l);
    }
    for (let c = q.confidence ? q.confidence[0] : 1;
         q.confidence && !confSlider && c <= q.confidence[1]; c++) {
      const l = el("label", {});
      l.appendChild(el("input", {type: "radio", name: "confidence", id: "confidence-" + c,
                                 value: String(c)}));
      l.appendChild(document.createTextNode(" " + c + " "));
      box.appendChild(l);
    }
    $("answers").appendChild(el("button", {id: "submit", onclick: async () => {
      if (busy) return;
      const c = confSlider ? $("confidence-slider")
                           : document.querySelector("input[name=confidence]:checked");
      if (q.confidence && !c) { showError("choose your confidence (1-5) first"); return; }
      setBusy(true);            // at once: a second click of a double-click finds it disabled
      while (sliderBusy) await new Promise((r) => setTimeout(r, 20));
      if (sliderFailed) {       // the last move never played: play it, then answer it
        try { await slide(); } catch (e) { setBusy(false); await reload(e); return; }
      }
      await answer(Object.assign(sliderValues(), q.confidence ? {confidence: Number(c.value)}
                                                              : {}));
    }}, "this is my match"));
  } else if (q.kind === "rate" && q.slider) {   // the lab's app: a continuous rating slider
    const [lo, hi] = q.slider.range;
    const l = el("label", {});
    l.appendChild(document.createTextNode(lo + " "));
    l.appendChild(el("input", {type: "range", id: "rating", min: lo, max: hi,
                               step: String(q.slider.step), value: String(q.slider.start)}));
    l.appendChild(document.createTextNode(" " + hi));
    $("answers").appendChild(l);
    $("answers").appendChild(el("button", {id: "submit-rating", onclick: () => {
      if (busy) return;
      setBusy(true);            // at once: a second click of a double-click finds it disabled
      answer(Number($("rating").value));
    }}, "submit this rating"));
  } else {
    // the level that plays (after a reload: the board's, not the question's start)
    level = q.level ? ((res.feel && res.feel.level !== undefined) ? res.feel.level
                                                                   : q.level.start) : null;
    if (q.level) {              // seed 003's friction slider: re-plays what is felt at once
      const l = el("label", {id: "level-box"});
      l.appendChild(document.createTextNode("friction: less "));
      l.appendChild(el("input", {type: "range", id: "level", min: q.level.range[0],
                                 max: q.level.range[1], step: String(q.level.step),
                                 value: String(level)}));
      l.appendChild(document.createTextNode(" more"));
      $("answers").appendChild(l);
      $("level").onchange = async () => {
        level = Number($("level").value);
        if (playingOption === null) return;       // (the next feel carries it)
        while (busy) await new Promise((r) => setTimeout(r, 20));   // (a feel under way)
        feel(playingOption);
      };
    }
    q.answers.forEach((a, i) => {
      $("answers").appendChild(el("button", {id: "answer-" + i, onclick: () => {
        if (busy) return;
        setBusy(true);          // at once: a second click of a double-click finds it disabled
        answer(withLevel(a));
      }}, label(q.kind, a, q)));
    });
  }
  if (q.seconds) {              // the staircase's 30 s per trial (seed 001): shown, not forced
    let left = q.seconds;
    $("timer").textContent = left + " s";
    timer = setInterval(() => {
      left -= 1;
      $("timer").textContent = left > 0 ? left + " s" : "time is up: please answer";
      if (left <= 0) clearInterval(timer);
    }, 1000);
  }
  const n = res.answers_so_far || 0;
  $("progress").textContent = (q.of ? "trial " + (q.trial + 1) + " of " +
                               (Array.isArray(q.of) ? q.of[0] : q.of) + " - " : "") +
                              n + " answer" + (n === 1 ? "" : "s");
}

(async () => {
  if (!sid) { showError("no session: open this page from the experimenter's screen"); return; }
  strip = await boardLine(false, {labels: false});     // blind: no region labels
  show(await call("GET", "/api/sessions/" + sid));
})();
