// texelpad lab: see and hear the playing scene (issue 11, point 5).
// A plain browser script (no build step, no framework):
//
//   const strip = window.texelpadStrip(canvas, {muteButton, onChange, base, pollMs, muted,
//                                               labels});
//     muteButton: the sound toggle (default: a button made after the canvas; null: none)
//     onChange(strip): after every refresh/show/error; base: URL prefix of the API
//     pollMs: refresh every pollMs while not dragging (0/absent: never)
//     muted: start muted; labels: false hides the region labels (a blind screen)
//     autoRefresh: false skips the first refresh() the strip does by itself
//     path: the GET that answers the strip (default "/api/strip"; the scene editor's
//           "/api/editor/strip" labels brush regions)
//     onSelect(startMm, endMm): span selection (the scene editor, static/editor.js): a
//           drag selects a span instead of moving the finger (a drag with Shift held,
//           or setMode("feel"), still feels); a click selects the region (or the gap)
//           under it. The ends snap to region boundaries and the display's ends within
//           SNAP_PX, and to the display's positions (the board rounds to them anyway).
//           Without onSelect nothing of this exists: a drag feels, as before.
//   await strip.refresh();             // GET /api/strip (options.path), redraw
//   strip.synth(x0_mm, x1_mm, seconds, sampleRate[, state]) -> Float32Array
//   strip.show(answer)               // draw a strip answer got elsewhere (POST /api/strip/texel)
//   strip.setMuted(bool); strip.audioState(); strip.muted; strip.data; strip.finger_mm; strip.sent; strip.scheduled
//   strip.select(startMm, endMm) / strip.select(null); strip.selection ({start_mm, end_mm} or
//   null); strip.setMode("select" | "feel"); strip.mode    (with options.onSelect)
//   strip.zoom(factor[, centerMm]); strip.setView(startMm, endMm) / strip.setView(null) (the
//   whole display); strip.view ({start_mm, end_mm}: the span drawn)
//     zoomButtons: the zoom buttons (default: made after the canvas; null: none). The wheel
//     over the strip zooms about the pointer (Shift + wheel, or a sideways wheel, pans):
//     a full-screen texture is 19,200 positions on a canvas of ~1,000 pixels, a solid
//     block of min..max at the whole display; zoomed in, each position's amplitude shows.
//
// The strip (host/texelpad/web/strip.py, GET /api/strip) is the amplitude the
// board plays at each display position (one uint8 each, 0..255 = 0..1), from
// the canonical scene rendered with the board's own code. Dragging on the
// canvas moves the virtual board's finger (POST /api/finger: at most ~30 a
// second, one in flight, the latest position wins, null on release) and plays
// the friction under the finger as sound: between two pointer events the
// finger goes x0 -> x1 mm in dt s, and the amplitude along that path is
// synthesised at the AudioContext's rate, so a texture of f cycles/mm swiped
// at v mm/s sounds at f*v Hz. Audio starts only after a user gesture (the
// browsers' autoplay policy): the AudioContext is made in a pointerdown or a
// click of the mute button.
(function () {
  "use strict";

  var FINGER_MIN_MS = 1000 / 30;  // at most ~30 finger requests a second
  var GAIN = 0.3;                 // output gain: the friction swings 0..1, high-passed +-0.5
  var HP_HZ = 20;                 // high-pass corner: a still finger is silent within ~25 ms
  var LEAD_S = 0.03;              // first buffer this far after now (scheduling slack)
  var AHEAD_MAX_S = 0.25;         // never queue more than this: keeps the latency down
  var DT_MAX_S = 0.1;             // a longer gap between pointer events is a pause
  var TAIL_S = 0.06;              // still-finger tail after a pause or a release: the
                                  // high-pass rings down instead of a click
  var PAUSE_MS = 40;              // no pointer event for this long: the finger stands
  var SNAP_PX = 6;                // selection: an end this near a boundary (CSS px) snaps to it
  var ZOOM_MIN_POSITIONS = 40;    // the narrowest view: this many display positions
  var ZOOM_STEP = 2;              // a button press or a wheel notch zooms by this factor
  var CLICK_PX = 3;               // selection: a drag shorter than this is a click

  function decode(b64) {
    var s = atob(b64), a = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) a[i] = s.charCodeAt(i);
    return a;
  }

  // The strip as the synthesis uses it: amp[i] in 0..1 for display position i
  // (position i covers [i - 0.5, i + 0.5) in position units: the board rounds
  // mm to the nearest position, texel.runtime.scene.to_position), and cum, the
  // prefix sums (cum[i] = amp[0] + ... + amp[i-1]) for averaging over a path.
  function model(data) {
    var u8 = decode(data.amplitude), n = u8.length;
    var amp = new Float32Array(n), cum = new Float64Array(n + 1);
    for (var i = 0; i < n; i++) {
      amp[i] = u8[i] / 255;
      cum[i + 1] = cum[i] + amp[i];
    }
    return {data: data, n: n, amp: amp, cum: cum,
            perMm: 1000 / data.dx_um,           // positions per mm (1 / 5.3 um on the TPaD)
            lengthMm: data.length_mm};
  }

  // Integral of the played amplitude (constant over each position's cell)
  // from the display's start (-0.5) to p, in position units.
  function integral(m, p) {
    if (p <= -0.5) return 0;
    if (p >= m.n - 0.5) return m.cum[m.n];
    var i = Math.floor(p + 0.5);        // the cell p is in
    return m.cum[i] + (p + 0.5 - i) * m.amp[i];
  }

  function ampAt(m, p) {
    var i = Math.floor(p + 0.5);
    return m.amp[i < 0 ? 0 : (i >= m.n ? m.n - 1 : i)];
  }

  // The friction along the path x0 -> x1 mm in `seconds`, at `rate` Hz:
  // sample k is the board's amplitude averaged over the stretch the finger
  // covers during that sample (a box filter: no aliasing when a fast swipe
  // crosses several positions per sample; the exact amplitude when it
  // crosses less than one), then a one-pole high-pass (corner HP_HZ) so the
  // constant part - a still finger, a constant region - is silent. `state`
  // ({x, y}: the filter's last input and output) carries the filter across
  // buffers played back to back; without it the filter starts at rest on
  // the first sample (a still finger gives exact zeros). Pure: reads only m.
  function synthOf(m, x0, x1, seconds, rate, state) {
    var n = Math.max(0, Math.round(seconds * rate));
    var out = new Float32Array(n);
    if (!m || n === 0) return out;
    var p0 = x0 * m.perMm, p1 = x1 * m.perMm, step = (p1 - p0) / n;
    var r = Math.exp(-2 * Math.PI * HP_HZ / rate);
    var st = state || {x: null, y: 0};
    var px = st.x, py = st.y;
    var fa = integral(m, p0);
    for (var k = 0; k < n; k++) {
      var pa = p0 + k * step, pb = pa + step, v;
      var fb = integral(m, pb);
      if (Math.abs(step) > 1e-6) v = (fb - fa) / step;
      else v = ampAt(m, 0.5 * (pa + pb));
      fa = fb;
      if (px === null) px = v;          // at rest on the first sample
      py = v - px + r * py;             // y[k] = x[k] - x[k-1] + r y[k-1]
      px = v;
      out[k] = py;
    }
    st.x = px; st.y = py;
    return out;
  }

  window.texelpadStrip = function (canvas, options) {
    options = options || {};
    var base = options.base || "";
    var path = options.path || "/api/strip";
    // sent: finger requests made; scheduled: sound buffers queued (for tests and curiosity)
    var self = {data: null, finger_mm: null, muted: !!options.muted, sent: 0, scheduled: 0,
                error: null, selection: null, mode: options.onSelect ? "select" : "feel"};
    var selecting = null;                    // a selection drag: {x0 (mm), px0 (client x)}
    var m = null, sized = false;
    // the span drawn, in mm (null: the whole display)
    var view = null;

    function span() {
      return view ? [view[0], view[1]] : [0, m ? m.lengthMm : 1];
    }

    // the canvas x (device pixels, w wide) of x mm in the view
    function xOf(x, w) {
      var v = span();
      return (x - v[0]) / (v[1] - v[0]) * w;
    }

    // the view [a, b] mm, kept on the display and at least ZOOM_MIN_POSITIONS wide
    function setView(a, b) {
      if (!m || a === null || a === undefined) { view = null; draw(); return; }
      var L = m.lengthMm, minW = Math.min(L, ZOOM_MIN_POSITIONS / m.perMm);
      var wdt = Math.max(minW, Math.min(L, b - a)), c = 0.5 * (a + b);
      a = c - wdt / 2;
      if (a < 0) a = 0;
      if (a + wdt > L) a = L - wdt;
      view = wdt >= L ? null : [a, a + wdt];
      draw();
    }

    function zoom(factor, centre) {
      if (!m) return;
      var v = span(), c = centre === undefined || centre === null ? 0.5 * (v[0] + v[1]) : centre;
      var f = (c - v[0]) / (v[1] - v[0]);  // the centre stays where it is on the canvas
      var wdt = (v[1] - v[0]) / factor;
      setView(c - f * wdt, c - f * wdt + wdt);
    }

    // A canvas sized by its width/height attributes alone (no CSS size) would
    // grow with every redraw at a device pixel ratio above 1 (draw() sets its
    // width to CSS pixels x ratio): at the first draw where it is shown, before
    // its attributes were ever changed, hold its CSS size where it is.
    function holdSize() {
      if (canvas.clientWidth === canvas.width && !canvas.style.width) {
        canvas.style.width = canvas.width + "px";
      }
      if (canvas.clientHeight === canvas.height && !canvas.style.height) {
        canvas.style.height = canvas.height + "px";
      }
      sized = true;
    }
    var dragging = false, last = null;       // last: {x (mm), t (ms, event time)}
    var audio = null, gainNode = null, nextT = 0, carry = 0, hp = {x: null, y: 0};
    var pauseTimer = null;
    // finger requests: one in flight; `pending` (an object, so null = lift can wait
    // its turn) is the latest position not sent yet
    var inFlight = false, pending = null, lastSent = -1e9, sendTimer = null;

    function api(method, path, body) {
      return fetch(base + path, {method: method, headers: {"content-type": "application/json"},
                                 body: body === undefined ? undefined : JSON.stringify(body)})
        .then(function (r) {
          return r.json().then(function (j) {
            if (!r.ok) throw new Error(j.error || r.statusText);
            return j;
          });
        });
    }

    // --- drawing -------------------------------------------------------------
    function draw() {
      if (!canvas.clientWidth || !canvas.clientHeight) return;     // hidden: drawn when shown
      if (!sized) holdSize();
      var dpr = window.devicePixelRatio || 1;
      var w = Math.max(1, Math.round(canvas.clientWidth * dpr));
      var h = Math.max(1, Math.round(canvas.clientHeight * dpr));
      if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
      var g = canvas.getContext("2d");
      g.fillStyle = "#fff"; g.fillRect(0, 0, w, h);
      if (!m) return;
      var band = Math.round(h * 0.35), top = band + Math.round(4 * dpr), wave = h - top - 2;
      // per pixel column: the mean as a grey level (white = amplitude 1, the
      // most friction reduction: slippery), min..max as the waveform below;
      // the columns cover the view's positions (the whole display: n / w each)
      var v = span(), p0 = v[0] * m.perMm, p1 = v[1] * m.perMm;
      for (var c = 0; c < w; c++) {
        var a = Math.floor(p0 + (p1 - p0) * c / w);
        var b = Math.max(a + 1, Math.floor(p0 + (p1 - p0) * (c + 1) / w));
        a = Math.max(0, Math.min(m.n - 1, a));
        b = Math.max(a + 1, Math.min(m.n, b));
        var lo = 1, hi = 0;
        for (var i = a; i < b; i++) { var v = m.amp[i]; if (v < lo) lo = v; if (v > hi) hi = v; }
        var mean = (m.cum[b] - m.cum[a]) / (b - a), grey = Math.round(mean * 255);
        g.fillStyle = "rgb(" + grey + "," + grey + "," + grey + ")";
        g.fillRect(c, 0, 1, band);
        g.fillStyle = "#36c";
        g.fillRect(c, top + (1 - hi) * wave, 1, Math.max(1, (hi - lo) * wave));
      }
      // region boundaries and labels (options.labels false: boundaries only -
      // a participant's screen shows no parameter values)
      var labels = options.labels !== false;
      g.font = Math.round(11 * dpr) + "px system-ui, sans-serif";
      g.textBaseline = "top";
      m.data.regions.forEach(function (r) {
        var xs = xOf(r.start_mm, w), xe = xOf(r.end_mm, w);
        if (xe < 0 || xs > w) return;                   // (outside the view)
        g.fillStyle = "#c60";
        g.fillRect(Math.round(xs), 0, Math.max(1, Math.round(dpr)), h);
        g.fillRect(Math.round(xe) - 1, 0, Math.max(1, Math.round(dpr)), h);
        g.fillStyle = "rgba(255,255,255,0.8)";
        var label = r.label;
        var tw = g.measureText(label).width;
        var lx = Math.max(xs, 0);
        if (labels && tw < Math.min(xe, w) - lx - 6 * dpr) {
          g.fillRect(lx + 3 * dpr, 2 * dpr, tw + 4 * dpr, 14 * dpr);
          g.fillStyle = "#000";
          g.fillText(label, lx + 5 * dpr, 3 * dpr);
        }
      });
      // the selected span (options.onSelect)
      if (self.selection) {
        var ss = xOf(self.selection.start_mm, w), se = xOf(self.selection.end_mm, w);
        g.fillStyle = "rgba(30,110,255,0.28)";
        g.fillRect(ss, 0, Math.max(1, se - ss), h);
        g.fillStyle = "#15f";
        g.fillRect(Math.round(ss), 0, Math.max(2, Math.round(2 * dpr)), h);
        g.fillRect(Math.round(se) - Math.max(2, Math.round(2 * dpr)), 0,
                   Math.max(2, Math.round(2 * dpr)), h);
      }
      // the zoom: which part of the display this is
      if (view) {
        g.fillStyle = "rgba(0,0,0,0.6)";
        g.font = Math.round(10 * dpr) + "px system-ui, sans-serif";
        g.textBaseline = "bottom";
        var t = view[0].toFixed(2) + " .. " + view[1].toFixed(2) + " mm of " +
                m.lengthMm.toFixed(2) + " (x" + (m.lengthMm / (view[1] - view[0])).toFixed(0) + ")";
        g.fillText(t, w - g.measureText(t).width - 4 * dpr, h - 2 * dpr);
      }
      self.view = {start_mm: span()[0], end_mm: span()[1]};
      // the finger
      if (self.finger_mm !== null) {
        var fx = xOf(self.finger_mm, w);
        g.fillStyle = "#d00";
        g.fillRect(Math.round(fx - dpr), 0, Math.max(2, Math.round(2 * dpr)), h);
      }
    }

    // a new display length: the whole display again
    function keepView(d) {
      if (view && (!self.data || d.length_mm !== self.data.length_mm)) view = null;
    }

    function refresh() {
      return api("GET", path).then(function (d) {
        keepView(d);
        if (!self.data || d.scene_id !== self.data.scene_id) m = model(d);
        else m.data = d;
        self.data = d;
        if (!dragging) self.finger_mm = d.finger_mm;
        self.error = null;
        draw();
        if (options.onChange) options.onChange(self);
        return d;
      }, function (e) { self.error = e.message; if (options.onChange) options.onChange(self); throw e; });
    }

    // a strip answer from elsewhere (POST /api/strip/texel answers with one)
    function show(d) {
      keepView(d);
      if (!self.data || d.scene_id !== self.data.scene_id) m = model(d);
      else m.data = d;                      // (as refresh: the same scene, its labels anew)
      self.data = d;
      draw();
      if (options.onChange) options.onChange(self);
    }

    // --- the finger on the virtual board ------------------------------------
    function sendFinger(x) {
      if (!self.data || !self.data.virtual) return;
      pending = {x: x};
      pump();
    }

    function pump() {
      if (inFlight || pending === null || sendTimer !== null) return;
      var wait = lastSent + FINGER_MIN_MS - performance.now();
      if (wait > 0) {
        sendTimer = setTimeout(function () { sendTimer = null; pump(); }, wait);
        return;
      }
      var x = pending.x;
      pending = null;
      inFlight = true;
      lastSent = performance.now();
      self.sent++;
      api("POST", "/api/finger", {position_mm: x === null ? null : Math.round(x * 1e4) / 1e4})
        .catch(function (e) { self.error = e.message; if (options.onChange) options.onChange(self); })
        .then(function () { inFlight = false; pump(); });
    }

    // --- sound ----------------------------------------------------------------
    function ensureAudio() {               // only ever called from a user gesture
      if (self.muted) return;
      var AC = window.AudioContext || window.webkitAudioContext;
      if (!AC) return;
      if (!audio) {
        audio = new AC();
        gainNode = audio.createGain();
        gainNode.gain.value = GAIN;
        gainNode.connect(audio.destination);
      }
      if (audio.state === "suspended") audio.resume();
    }

    function play(x0, x1, seconds) {
      if (self.muted || !audio || !m || seconds <= 0) return;
      var now = audio.currentTime;
      if (nextT < now + 0.005) {            // nothing queued (a pause, or the start)
        nextT = now + LEAD_S;
      } else if (nextT > now + AHEAD_MAX_S) {
        return;                             // too far behind: skip, catch up with the finger
      }
      // whole samples, the fraction carried to the next buffer: the buffers'
      // durations add up to the pointer's own time (no pitch drift)
      var rate = audio.sampleRate, total = seconds * rate + carry, n = Math.floor(total);
      carry = total - n;
      if (n === 0) return;
      var s = synthOf(m, x0, x1, n / rate, rate, hp);
      var buf = audio.createBuffer(1, s.length, rate);
      buf.getChannelData(0).set(s);
      var src = audio.createBufferSource();
      src.buffer = buf;
      src.connect(gainNode);
      src.start(nextT);
      nextT += s.length / rate;
      self.scheduled++;
    }

    function stillTail(x) {
      if (x !== null) play(x, x, TAIL_S);
    }

    function showMuted() {
      var b = options.muteButton;
      if (!b) return;
      b.textContent = self.muted ? "sound: off (click to hear)" : "sound: on (click to mute)";
      b.setAttribute("aria-pressed", String(!self.muted));
    }

    // call it from a user gesture (a click): unmuting may start the audio
    function setMuted(v) {
      self.muted = !!v;
      if (self.muted) {
        if (audio) audio.suspend();
      } else {
        ensureAudio();
      }
      showMuted();
    }

    // --- pointer --------------------------------------------------------------
    function mmOf(e) {
      var rect = canvas.getBoundingClientRect();
      var f = (e.clientX - rect.left) / Math.max(1, rect.width);
      f = f < 0 ? 0 : (f > 1 ? 1 : f);
      var v = span();
      return m ? v[0] + f * (v[1] - v[0]) : 0;
    }

    // the finger at x mm at event time t (ms): the sound of the way there
    function step(x, t) {
      var dt = last ? (t - last.t) / 1000 : 0;
      if (last && dt > 0) play(last.x, x, Math.min(dt, DT_MAX_S));
      last = {x: x, t: t};
    }

    function move(x) {
      self.finger_mm = x;
      sendFinger(x);
      draw();
      clearTimeout(pauseTimer);
      pauseTimer = setTimeout(function () { if (dragging && last) stillTail(last.x); }, PAUSE_MS);
    }

    // --- span selection (options.onSelect) ----------------------------------------
    // x mm on the display's positions, snapped to a region boundary or an end
    // of the display within SNAP_PX CSS pixels
    function snap(x) {
      var v = span();
      var rect = canvas.getBoundingClientRect(), mmPerPx = (v[1] - v[0]) / Math.max(1, rect.width);
      var best = null, bestD = SNAP_PX * mmPerPx;
      var edges = [0, m.lengthMm];
      m.data.regions.forEach(function (r) { edges.push(r.start_mm, r.end_mm); });
      edges.forEach(function (c) {
        var d = Math.abs(c - x);
        if (d <= bestD) { best = c; bestD = d; }
      });
      if (best !== null) return best;
      return Math.round(Math.round(x * m.perMm) / m.perMm * 1e4) / 1e4;
    }

    // a click: the region under x, else the gap around it (between its neighbours)
    function spanAt(x) {
      var lo = 0, hi = m.lengthMm;
      for (var i = 0; i < m.data.regions.length; i++) {
        var r = m.data.regions[i];
        if (x >= r.start_mm && x < r.end_mm) return [r.start_mm, r.end_mm];
        if (r.end_mm <= x && r.end_mm > lo) lo = r.end_mm;
        if (r.start_mm > x && r.start_mm < hi) hi = r.start_mm;
      }
      return [lo, hi];
    }

    function select(a, b) {
      if (a === null || a === undefined) self.selection = null;
      else self.selection = {start_mm: Math.min(a, b), end_mm: Math.max(a, b)};
      draw();
    }

    canvas.addEventListener("pointerdown", function (e) {
      if (!m) return;
      if (options.onSelect && self.mode === "select" && !e.shiftKey) {
        e.preventDefault();
        try { canvas.setPointerCapture(e.pointerId); } catch (err) { /* synthetic events */ }
        var x0 = snap(mmOf(e));
        selecting = {x0: x0, px0: e.clientX};
        select(x0, x0);
        return;
      }
      e.preventDefault();
      ensureAudio();                        // a user gesture: audio may start now
      dragging = true;
      hp = {x: null, y: 0};                 // a new touch: the filter starts at rest
      last = null;
      try { canvas.setPointerCapture(e.pointerId); } catch (err) { /* synthetic events */ }
      step(mmOf(e), e.timeStamp);
      move(last.x);
    });
    canvas.addEventListener("pointermove", function (e) {
      if (selecting) {
        select(selecting.x0, snap(mmOf(e)));
        return;
      }
      if (!dragging) return;
      // every pointer sample of this frame for the sound, one redraw and request
      var evs = e.getCoalescedEvents ? e.getCoalescedEvents() : [];
      if (evs.length > 1) evs.forEach(function (c) { step(mmOf(c), c.timeStamp); });
      else step(mmOf(e), e.timeStamp);
      move(last.x);
    });
    function endSelect(e) {
      var sel = selecting;
      selecting = null;
      if (Math.abs(e.clientX - sel.px0) < CLICK_PX) {
        var span = spanAt(mmOf(e));
        select(span[0], span[1]);
      } else {
        select(sel.x0, snap(mmOf(e)));
      }
      if (self.selection.end_mm > self.selection.start_mm) {
        options.onSelect(self.selection.start_mm, self.selection.end_mm);
      }
    }

    function release(e) {
      if (selecting) { endSelect(e); return; }
      if (!dragging) return;
      dragging = false;
      clearTimeout(pauseTimer);
      if (last) stillTail(last.x);
      last = null;
      self.finger_mm = null;
      sendFinger(null);                     // lifted (queued behind one in flight)
      draw();
    }
    canvas.addEventListener("pointerup", release);
    canvas.addEventListener("pointercancel", release);
    canvas.style.touchAction = "none";      // a drag on a touch screen is not a scroll

    // a page closed or left mid-drag (or with the lift still queued) must not
    // leave the virtual finger down: a keepalive request outlives the page
    window.addEventListener("pagehide", function () {
      if (self.data && self.data.virtual && (dragging || inFlight || pending !== null)) {
        fetch(base + "/api/finger", {method: "POST", keepalive: true,
                                     headers: {"content-type": "application/json"},
                                     body: JSON.stringify({position_mm: null})})
          .catch(function () {});
      }
    });

    // options.pollMs: redraw what plays and where the board senses the finger
    // every pollMs (a real board's own finger, another tab's push); 0 = never
    if (options.pollMs > 0) {
      setInterval(function () { if (!dragging) refresh().catch(function () {}); },
                  Math.max(200, options.pollMs));
    }

    // the mute toggle: options.muteButton, or one made after the canvas
    // (options.muteButton null: none)
    if (options.muteButton === undefined && canvas.parentNode && document.createElement) {
      var mb = document.createElement("button");
      mb.type = "button";
      mb.className = "strip-mute";
      canvas.parentNode.insertBefore(mb, canvas.nextSibling);
      options.muteButton = mb;
    }
    if (options.muteButton) {
      options.muteButton.addEventListener("click", function () { setMuted(!self.muted); });
    }

    // zoom: the wheel about the pointer (Shift or a sideways wheel pans), and
    // buttons (options.zoomButtons null: none)
    canvas.addEventListener("wheel", function (e) {
      if (!m) return;
      e.preventDefault();
      var v = span(), dx = e.shiftKey ? e.deltaY : e.deltaX;
      if (Math.abs(dx) > Math.abs(e.shiftKey ? 0 : e.deltaY)) {
        var shift = (v[1] - v[0]) * (dx > 0 ? 0.2 : -0.2);
        if (view) setView(v[0] + shift, v[1] + shift);
        return;
      }
      zoom(e.deltaY < 0 ? ZOOM_STEP : 1 / ZOOM_STEP, mmOf(e));
    }, {passive: false});
    if (options.zoomButtons === undefined && canvas.parentNode && document.createElement) {
      var zb = document.createElement("span");
      zb.className = "strip-zoom";
      [["zoom-in", "zoom in", function () { zoom(ZOOM_STEP); }],
       ["zoom-out", "zoom out", function () { zoom(1 / ZOOM_STEP); }],
       ["zoom-all", "whole display", function () { setView(null); }]].forEach(function (b) {
        var el = document.createElement("button");
        el.type = "button";
        el.className = "strip-" + b[0];
        el.textContent = b[1];
        el.addEventListener("click", b[2]);
        zb.appendChild(el);
      });
      canvas.parentNode.insertBefore(zb, canvas.nextSibling);
    }
    showMuted();                            // no AudioContext before a gesture
    // redraw at every size change (a hidden strip shown, a window resized)
    if (window.ResizeObserver) new ResizeObserver(function () { draw(); }).observe(canvas);
    else window.addEventListener("resize", draw);

    self.refresh = refresh;
    self.show = show;
    self.draw = draw;
    self.setMuted = setMuted;
    self.select = select;
    self.zoom = zoom;
    self.setView = function (a, b) { setView(a, b); };
    self.setMode = function (mode) { self.mode = mode === "feel" ? "feel" : "select"; };
    self.audioState = function () { return audio ? audio.state : "none"; };
    // drawn at once (options.autoRefresh false: only when refresh() is called)
    if (options.autoRefresh !== false) refresh().catch(function () {});
    self.synth = function (x0, x1, seconds, rate, state) {
      return synthOf(m, x0, x1, seconds, rate, state);
    };
    return self;
  };
})();
