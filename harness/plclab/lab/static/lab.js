// The virtual lab page: a view of the stand the server runs. State comes over the WebSocket;
// every control sends a command and shows what the server answered. Plain JS, no library.
"use strict";

const $ = (sel) => document.querySelector(sel);
const el = (tag, attrs = {}, ...children) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "text") e.textContent = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
};

const lab = {
  ws: null, hello: null, state: null, nextId: 1, pending: new Map(),
  trends: new Map(),          // name -> [[t, v], ...]
  trendNames: [], events: [], actions: [], retry: 0, trendWindow: 60, watched: [],
};

// ------------------------------------------------------------------ connection
// The lab answers only its own page: every command carries the token of this run of the
// lab, read from /api/session (another site's page cannot read it). A restarted lab has a
// new token and a new session: the page reads them again when it reconnects.
async function connect() {
  try {
    const r = await fetch("/api/session", { cache: "no-store" });
    const info = await r.json();
    lab.token = info.token;
  } catch (e) {
    lab.token = null;
  }
  if (!lab.token) { lost(); return; }
  const proto = location.protocol === "https:" ? "wss" : "ws";
  const ws = new WebSocket(`${proto}://${location.host}/ws?token=${encodeURIComponent(lab.token)}`);
  lab.ws = ws;
  ws.onopen = () => { lab.retry = 0; $("#conn").textContent = ""; };
  ws.onmessage = (ev) => {
    let msg;
    try { msg = JSON.parse(ev.data); } catch (e) { return; }
    if (msg.type === "hello") onHello(msg);
    else if (msg.type === "state") onState(msg);
    else if (msg.type === "reply") onReply(msg);
    else if (msg.type === "notice") notice(msg.text);
    else if (msg.type === "pages") showPages(msg.pages);
    else if (msg.type === "trends") setTrends(msg.names, msg.trends);
  };
  ws.onclose = () => { if (lab.ws === ws) lost(); };
}

// Connection lost: the page says so everywhere (badge, clock, controls), and no control can be
// used until the lab answers again; what it then shows starts afresh from the lab's state.
function lost() {
  lab.ws = null;
  lab.state = null;
  document.body.classList.add("offline");
  const badge = $("#plc-state");
  badge.textContent = "no connection";
  badge.dataset.state = "OFFLINE";
  $("#clock").textContent = "t = ? s";
  $("#speed-shown").textContent = "";
  setControlsEnabled(false);
  for (const r of releasers) r();
  $("#conn").textContent = "connection to the lab lost: reconnecting...";
  for (const [, p] of lab.pending) p.reject(new Error("connection lost"));
  lab.pending.clear();
  const delay = Math.min(5000, 250 * 2 ** lab.retry++);
  setTimeout(connect, delay);
}

// every control of the page, on or off (the Single scan button is on only while paused)
function setControlsEnabled(on) {
  for (const c of document.querySelectorAll("main button, main input, main select")) {
    if (on) { if (c.dataset.offline) { c.disabled = false; delete c.dataset.offline; } }
    else if (!c.disabled) { c.disabled = true; c.dataset.offline = "1"; }
  }
}

// POST to the lab with this run's token (a JSON or multipart body)
function post(url, body, json) {
  const headers = { "X-PLCLab-Token": lab.token || "" };
  if (json) headers["content-type"] = "application/json";
  return fetch(url, { method: "POST", headers, body: json ? JSON.stringify(body) : body });
}

function send(op, fields = {}) {
  return new Promise((resolve, reject) => {
    if (!lab.ws || lab.ws.readyState !== WebSocket.OPEN) {
      reject(new Error("not connected to the lab"));
      return;
    }
    const id = lab.nextId++;
    lab.pending.set(id, { resolve, reject });
    lab.ws.send(JSON.stringify({ op, id, ...fields }));
  });
}

function onReply(msg) {
  const p = lab.pending.get(msg.id);
  if (!p) { if (!msg.ok) notice(msg.message); return; }
  lab.pending.delete(msg.id);
  if (msg.ok) p.resolve(msg); else p.reject(new Error(msg.message));
}

function notice(text) {
  lab.actions.push({ t: lab.state ? lab.state.t : 0, text: "(lab) " + text });
  renderActions();
}

function showPages(n) { $("#pages").textContent = n > 1 ? `${n} pages open` : ""; }

function say(target, text, ok) {
  const t = $(target);
  t.textContent = text;
  t.className = ok ? "good" : "bad";
}

// ------------------------------------------------------------------ building the page
function onHello(h) {
  const restarted = lab.hello && lab.hello.session !== h.session;
  lab.hello = h;
  document.body.classList.remove("offline");
  setControlsEnabled(true);
  // a fresh log: what the lab sends now is its whole history (a restarted lab: a new one)
  lab.events = []; lab.actions = [];
  renderEvents(); renderActions();
  if (restarted) {
    for (const id of ["#program-message", "#program-errors", "#grade-message", "#grade-result", "#fault-message",
                      "#register-message"]) $(id).replaceChildren();
    notice("the lab was restarted: a new session");
  }
  if (h.grade && !$("#grade-result").children.length) renderGrade(h.grade);     // the last grade, kept by the lab
  document.title = `PLC Lab: ${h.title}`;
  $("#title").textContent = h.title;
  showPages(h.pages);
  buildControls(h.panel);
  buildRun(h);
  buildFaults(h.panel);
  buildGrade(h);
  buildWatch();
  buildOnline();
  $("#registers").hidden = h.stand !== "thermo";
  $("#twido").textContent = h.twido ? `The Twido Modbus face answers at ${h.twido} (holding register n = %MWn) for an external SCADA client.` : "";
  Mimic.build($("#mimic"), h.stand, h.panel);
  const placed = Mimic.placed();
  const lamps = $("#lamps");
  lamps.replaceChildren();
  for (const lamp of h.panel.lamps) {
    if (placed.has(lamp.label)) continue;
    lamps.append(el("span", { class: "lamp", role: "img", "aria-label": lamp.label, "data-state": "off", title: lamp.hint },
      el("span", { class: "bulb" }), el("span", { text: lamp.label })));
  }
  lab.trends.clear();
  lab.trendWindow = h.trend_window;
  $("#h-trends").textContent = `Trends (last ${h.trend_window} s of plant time)`;
  lab.trendNames = h.trend_names.slice();
  buildTrendList();
}

// what the console's push buttons do, said for the stand on the page
const HOLD_NOTE = "Round buttons are push buttons: pressed while you hold them (mouse, finger, space or enter key). " +
  "While you hold one the plant runs in real time (x1) whatever the speed, so a hold lasts as long in the plant as you hold it";
const HOLD_NOTES = {
  mp9c: " (SB1: a click records a frame or starts / stops playback, a 3-s hold resets).",
  tur10: " (SB1: a click records a frame or starts / stops playback, a 3-s hold resets; SA1..SA5 forward / backward " +
    "move their link while held).",
  cnc: " (SB1 starts or continues the part program, SB2 holds the feed). SB3, the emergency stop, is a mushroom " +
    "button: a click latches it pressed, another click releases it.",
};

// a part program's name: its first comment (the handout's programs start with one), else a number
function partName(text) {
  const comment = /^\s*\(([^)]+)\)/m.exec(text);
  lab.parts = (lab.parts || 0) + 1;
  return comment && comment[1].trim() ? comment[1].trim().slice(0, 60) : `part ${lab.parts}`;
}

function buildControls(panel) {
  const box = $("#controls");
  box.replaceChildren();
  // forward / backward pairs (TUR-10's jog buttons) keep to one row
  box.classList.toggle("paired", panel.controls.some((c) => / forward$/.test(c.label)));
  for (const c of panel.controls) {
    let b;
    if (c.kind === "switch") {
      b = el("button", { type: "button", role: "switch", "aria-checked": "false", "aria-label": c.label, "data-label": c.label },
        el("span", { text: c.label }));
      b.addEventListener("click", () => {
        const on = b.getAttribute("aria-checked") !== "true";
        send("set", { label: c.label, value: on ? 1 : 0 }).catch((e) => notice(e.message));
      });
    } else if (c.latching) {              // a mushroom button: a press latches it, the next one releases it
      b = el("button", { type: "button", class: "push latch", "aria-pressed": "false", "aria-label": c.label,
        "data-label": c.label, "data-latch": "1" }, el("span", { text: c.label }));
      b.addEventListener("click", () => {
        const pressed = b.getAttribute("aria-pressed") === "true";
        send(pressed ? "release" : "press", { label: c.label }).catch((e) => notice(e.message));
      });
    } else {
      b = el("button", { type: "button", class: "push", "aria-pressed": "false", "aria-label": c.label, "data-label": c.label },
        el("span", { text: c.label }));
      pushButton(b, c.label);
    }
    const hint = el("small", { id: `hint-${c.label.replace(/\W/g, "_")}`, text: c.hint });
    b.setAttribute("aria-describedby", hint.id);
    box.append(el("div", { class: "control" }, b, hint));
  }
  $("#hold-note").hidden = !panel.controls.some((c) => c.kind === "button");
  $("#hold-note").textContent = HOLD_NOTE + (HOLD_NOTES[panel.stand] || "");
  // settings that are not contacts (the CNC's feed override RP1 and backlash): a slider each
  const knobs = $("#knobs");
  knobs.replaceChildren();
  for (const k of panel.knobs || []) {
    const id = `knob-${k.label}`;
    const out = el("output", { for: id, text: `${k.initial} ${k.unit}` });
    const range = el("input", { id, type: "range", min: String(k.lo), max: String(k.hi), value: String(k.initial),
      "aria-label": k.label, "data-knob": k.label });
    range.oninput = () => { out.textContent = `${range.value} ${k.unit}`; };
    range.onchange = () => send("knob", { label: k.label, value: Number(range.value) }).catch((e) => notice(e.message));
    knobs.append(el("div", { class: "knob" }, el("label", { for: id, text: `${k.label}: ${k.hint}` }), range, out));
  }
  // the CNC's part program
  const part = panel.part;
  $("#part").hidden = !part;
  if (part) {
    $("#part-text").value = part.example;
    $("#part-method").replaceChildren(...part.methods.map((m) => el("option", { value: m, text: m, title: METHODS[m] || "" })));
    $("#part-load").onclick = () => send("part", { text: $("#part-text").value, name: partName($("#part-text").value),
      method: $("#part-method").value })
      .then(() => say("#part-message", "part program loaded: press SB1 to run it", true))
      .catch((e) => say("#part-message", e.message, false));
  }
}

// the interpolation methods, as the handout names them (a tooltip on the choice and the drawing)
const METHODS = {
  evalfn: "evalfn: the evaluation-function method (a step on X or Y by the sign of the deviation function)",
  dda: "dda: the digital differential analyser (pulses from accumulators that overflow)",
  integration: "integration: digital integration (accumulated increments per interpolation cycle)",
};

// A push button stays pressed while the pointer (mouse, finger, pen) or the space / enter key
// holds it, as on the stand: it is let go on pointerup, when the pointer leaves it, when the
// touch is cancelled, when it loses the focus and when the window does.
const releasers = new Set();
window.addEventListener("blur", () => { for (const r of releasers) r(); });
document.addEventListener("visibilitychange", () => { if (document.hidden) for (const r of releasers) r(); });

function pushButton(b, label) {
  let down = false;
  const press = () => {
    if (down || b.disabled) return;
    down = true;
    b.classList.add("held");
    b.setAttribute("aria-pressed", "true");
    send("press", { label }).catch((e) => notice(e.message));
  };
  const release = () => {
    if (!down) return;
    down = false;
    b.classList.remove("held");
    b.setAttribute("aria-pressed", "false");
    send("release", { label }).catch((e) => notice(e.message));
  };
  releasers.add(release);
  b.addEventListener("pointerdown", (e) => { if (e.button === 0) { press(); e.preventDefault(); } });
  b.addEventListener("pointerup", release);
  b.addEventListener("pointerleave", release);
  b.addEventListener("pointercancel", release);
  b.addEventListener("contextmenu", (e) => e.preventDefault());      // a long touch is a hold, not a menu
  b.addEventListener("keydown", (e) => {
    if ((e.key === " " || e.key === "Enter") && !e.repeat) { press(); e.preventDefault(); }
  });
  b.addEventListener("keyup", (e) => { if (e.key === " " || e.key === "Enter") { release(); e.preventDefault(); } });
  b.addEventListener("blur", release);
  b.addEventListener("click", (e) => e.preventDefault());
}

function buildRun(h) {
  const speed = $("#speed");
  speed.replaceChildren(...h.speeds.map((s) => el("option", { value: String(s), text: `x${s}` })));
  speed.onchange = () => send("speed", { value: Number(speed.value) }).catch((e) => notice(e.message));
  $("#pause").onclick = () => {
    const paused = lab.state && lab.state.paused;
    send(paused ? "run" : "pause").catch((e) => notice(e.message));
  };
  $("#scan").onclick = () => send("scan").catch((e) => notice(e.message));
  $("#restart").onclick = () => send("restart").catch((e) => notice(e.message));
  $("#reload").onclick = () => postProgram("/api/reload", null);
  const script = $("#script-file");
  script.onchange = async () => {
    const f = script.files[0];
    script.value = "";
    if (!f) return;
    let answer;
    try {
      const r = await post(`/api/script?name=${encodeURIComponent(f.name)}`, await f.arrayBuffer(), false);
      answer = await r.json();
    } catch (e) { answer = { ok: false, message: `the lab did not answer (${e.message})` }; }
    say("#script-status", answer.message, answer.ok);
  };
  $("#script-stop").onclick = () => send("unscript").catch((e) => notice(e.message));
  const input = $("#program-files");
  input.onchange = () => { if (input.files.length) uploadFiles(input.files); input.value = ""; };
  const drop = $("#drop");
  drop.ondragover = (e) => { e.preventDefault(); drop.classList.add("over"); };
  drop.ondragleave = () => drop.classList.remove("over");
  drop.ondrop = (e) => {
    e.preventDefault();
    drop.classList.remove("over");
    if (e.dataTransfer.files.length) uploadFiles(e.dataTransfer.files);
  };
}

function uploadFiles(files) {
  const form = new FormData();
  for (const f of files) form.append("files", f, f.name);
  postProgram("/api/program", form);
}

async function postProgram(url, body) {
  say("#program-message", "checking...", true);
  $("#program-errors").replaceChildren();
  let answer;
  try {
    const r = await post(url, body, false);
    answer = r.headers.get("content-type")?.includes("json") ? await r.json()
      : { ok: false, message: `${r.status} ${r.statusText}: ${(await r.text()).slice(0, 200)}` };
  } catch (e) {
    answer = { ok: false, message: `the lab did not answer (${e.message})` };
  }
  say("#program-message", answer.message, answer.ok);
  const list = $("#program-errors");
  for (const err of answer.errors || []) {
    const li = el("li", { text: err.text });
    if (err.source !== null && err.source !== undefined) li.append(el("pre", { text: `${String(err.line).padStart(4)} | ${err.source}` }));
    list.append(li);
  }
}

function buildFaults(panel) {
  const sel = $("#fault-name");
  sel.replaceChildren(...panel.faults.map((f) => el("option", { value: f.name, text: `${f.name}: ${f.text}` })));
  const params = () => {
    const f = panel.faults.find((x) => x.name === sel.value);
    const box = $("#fault-params");
    box.replaceChildren();
    for (const p of (f ? f.params : [])) {
      const id = `fault-param-${p.name}`;
      box.append(el("label", { for: id, text: p.name }));
      if (p.choices.length) {
        const s = el("select", { id, "data-param": p.name });
        s.append(...p.choices.map((c) => el("option", { value: c, text: c })));
        s.value = p.default;
        box.append(s);
      } else {
        box.append(el("input", { id, "data-param": p.name, value: p.default, size: "6" }));
      }
    }
  };
  sel.onchange = params;
  params();
  $("#inject").onclick = () => {
    const values = {};
    for (const x of document.querySelectorAll("#fault-params [data-param]")) values[x.dataset.param] = x.value;
    send("inject", { fault: sel.value, params: values })
      .then(() => say("#fault-message", `${sel.value} injected`, true))
      .catch((e) => say("#fault-message", e.message, false));
  };
  $("#clear").onclick = () => send("clear").then(() => say("#fault-message", "faults cleared", true))
    .catch((e) => say("#fault-message", e.message, false));
}

function buildGrade(h) {
  const box = $("#grade-buttons");
  box.replaceChildren();
  if (!h.tasks.length) box.append(el("span", { text: "no task of this stand is graded in the lab: try the SCADA tasks on the registers below, then grade them with plclab grade thermo scada1 (or scada2)" }));
  for (const task of h.tasks) {
    box.append(el("button", { type: "button", text: `Grade ${task}`, onclick: () => grade(task) }));
  }
  // what each task checks, before grading: the rows the grade table will have
  const checks = $("#grade-checks");
  checks.replaceChildren();
  for (const task of h.tasks) {
    const rows = (h.checks && h.checks[task]) || [];
    const table = el("table", { "aria-label": `requirements ${task}` },
      el("thead", {}, el("tr", {}, el("th", { text: "id" }), el("th", { text: "requirement" }))),
      el("tbody", {}, ...rows.map(([id, text]) => el("tr", {}, el("td", { text: id }), el("td", { text })))));
    checks.append(el("details", {}, el("summary", { text: `What ${task} checks (${rows.length} requirements)` }), table));
  }
}

async function grade(task) {
  say("#grade-message", `grading ${task} (runs the task's scenarios on the loaded program)...`, true);
  $("#grade-result").replaceChildren();
  let r;
  try {
    const resp = await post("/api/grade", { task }, true);
    r = await resp.json();
  } catch (e) {
    r = { ok: false, message: `the lab did not answer (${e.message})` };
  }
  if (!r.ok) { say("#grade-message", r.message, false); return; }
  renderGrade(r);
}

// A grade's table (also the last one again, when the page is reloaded: the lab keeps it)
function renderGrade(r) {
  const task = r.task;
  $("#grade-result").replaceChildren();
  say("#grade-message", `${r.title.replace(/[.:\s]+$/, "")}: ${r.summary}` + (r.program ? ` (program: ${r.program})` : ""),
    r.passed);
  const out = $("#grade-result");
  if (r.errors.length) {
    out.append(el("ol", {}, ...r.errors.map((e) => el("li", { class: "bad", text: e }))));
    return;
  }
  const table = el("table", { "aria-label": `grade ${task}` },
    el("thead", {}, el("tr", {}, ...["id", "requirement", "result", "why", "trace"].map((x) => el("th", { text: x })))));
  const body = el("tbody");
  for (const row of r.rows) {
    const why = row.result !== "PASS"          // FAIL, and NOT CHECKED / ERROR with their reason
      ? [row.expected && `expected: ${row.expected}`, row.observed && (row.result === "FAIL" ? `observed: ${row.observed}` : row.observed),
         row.time !== null && row.time !== undefined ? `at t = ${row.time.toFixed(2)} s` : ""].filter(Boolean).join("; ")
      : "";
    const links = el("td");
    if (row.result !== "PASS") {
      for (const t of row.traces) links.append(el("a", { href: t.url, download: t.name, text: t.name }), " ");
    }
    const whyCell = el("td", { text: why });
    const where = /(<[^>]+>|[^\s:]+\.st):(\d+)/.exec(`${row.observed || ""} ${row.expected || ""} ${row.text}`);
    if (row.graded && row.result !== "PASS") whyCell.append(el("div", { class: "graded", text: row.graded }));
    if (where) {
      whyCell.append(" ", el("button", { type: "button", class: "link", text: `open ${where[1].split("/").pop()}:${where[2]}`,
        onclick: () => openSource(where[1].trim(), Number(where[2]), { ...row, run: r.run }) }));
    }
    body.append(el("tr", {}, el("td", { text: row.id }), el("td", { text: row.text }),
      el("td", { class: row.result, text: row.result }), whyCell, links));
  }
  table.append(body);
  out.append(table);
}

// ------------------------------------------------------------------ state
// Data is taken as it comes; the page is drawn with the newest, in an animation frame, at
// most once every DRAW_EVERY_MS: about 25 drawings a second, smooth to the eye. Drawing at
// the display's rate (60 a second) made the browser spend most of a core on a page that
// only watches the stand, for nothing a person sees.
const DRAW_EVERY_MS = 40;
let drawScheduled = false;
let lastDrawn = -Infinity;
function scheduleDraw() {
  if (drawScheduled) return;
  drawScheduled = true;
  const draw = () => { drawScheduled = false; lastDrawn = performance.now(); if (lab.state) render(lab.state); };
  const wait = lastDrawn + DRAW_EVERY_MS - performance.now();
  if (wait <= 0) requestAnimationFrame(draw);
  else setTimeout(() => requestAnimationFrame(draw), Math.ceil(wait));   // whole ms: never early
}
function onState(s) {
  if (lab.state && s.epoch !== lab.state.epoch) {     // the stand was reset (an input script): start afresh
    lab.trends = new Map(); lab.events = []; lab.actions = [];
    lab.dirtyEvents = lab.dirtyActions = true;
  }
  lab.state = s;
  // the lab's watch list, taken when the state comes (not when drawn): a state that came before
  // the reply to the page's own watch command is older than that command, and drawn after the
  // reply it would undo it (the next pick then sent the old list and dropped a variable)
  if (!lab.watchPending) lab.watched = (s.watch || []).map((r) => r[0]);
  if ("frames" in s) { lab.frames = s.frames; lab.dirtyFrames = true; }
  if (s.monitor) {                           // changes only: kept until drawn (several may come per frame)
    const p = lab.pendingMonitor;
    lab.pendingMonitor = p && p.pou === s.monitor.pou && p.instance === s.monitor.instance
      ? { ...s.monitor, values: { ...p.values, ...s.monitor.values } } : s.monitor;
  }
  if (s.events.length) lab.events.push(...s.events);
  if (s.actions.length) lab.actions.push(...s.actions);
  for (const [name, points] of Object.entries(s.trends)) addPoints(name, points);
  lab.dirtyEvents ||= s.events.length > 0;
  lab.dirtyActions ||= s.actions.length > 0;
  scheduleDraw();
}

function render(s) {
  const badge = $("#plc-state");
  const pausedRun = s.paused && s.plc.state === "RUN";      // the PLC in RUN, the lab's clock stopped
  setText(badge, pausedRun ? "RUN, paused" : s.plc.state);
  setAttr(badge, "data-state", pausedRun ? "PAUSED" : s.plc.state);
  setAttr(badge, "title", pausedRun ? "the PLC is in RUN mode but the lab's clock is paused: no scan runs until Run (or Single scan)"
    : s.plc.state === "FAULT" ? "the PLC stopped on a fault: see the line below" : "");
  const fd = $("#fault-detail");
  if (s.plc.fault) {
    setProp(fd, "hidden", false);
    if (fd.dataset.fault !== s.plc.fault) {          // the fault, a way to its statement, and what to do next
      fd.dataset.fault = s.plc.fault;
      const where = s.plc.file ? `${s.plc.file.split("/").pop()}:${s.plc.line}` : null;
      fd.replaceChildren(el("span", { class: "fault-text", text: s.plc.fault }), " ",
        ...(where ? [el("button", { type: "button", class: "link fault-open", text: `open ${where} in Program online` })] : []),
        el("span", { class: "fault-next", text: " Next: correct the program and load it again, or Restart PLC " +
          "to run it once more (the PLC stays in FAULT, every output off, until one of them)." }));
    }
  } else if (!fd.hidden || fd.dataset.fault !== undefined) { fd.hidden = true; delete fd.dataset.fault; }
  setText($("#clock"), `t = ${s.t.toFixed(2)} s`);
  const held = s.held_labels || [];
  setText($("#speed-shown"), s.paused ? "paused"
    : held.length && s.speed !== 1 ? `x1 while ${held.join(", ")} held (then x${s.speed})`
    : `x${s.speed}` + (!held.length && s.actual_speed && s.actual_speed < s.speed * 0.9 ? ` (reaching x${s.actual_speed})` : ""));
  setText($("#pause"), s.paused ? "Run" : "Pause");
  setAttr($("#pause"), "aria-pressed", s.paused ? "true" : "false");
  setProp($("#scan"), "disabled", !s.paused);
  const speed = $("#speed");
  if (document.activeElement !== speed) {
    if (![...speed.options].some((o) => o.value === String(s.speed)))      // --speed 0.5: shown too
      speed.append(el("option", { value: String(s.speed), text: `x${s.speed}` }));
    setProp(speed, "value", String(s.speed));
  }
  setText($("#program-name"), s.program);
  const refused = $("#start-refused");
  setProp(refused, "hidden", !s.start_refused);
  setText(refused, s.start_refused || "");
  renderScript(s.script);
  if (s.loads !== lab.loads) {               // another program: the online listing is read again
    const shown = lab.pous !== null && lab.pous !== undefined;
    lab.loads = s.loads;
    buildOnline();
    if (shown) loadSource().catch((e) => notice(e.message));
  }
  setText($("#trace-window"), `The trace downloads hold t = ${s.trace_from.toFixed(0)} .. ${s.t.toFixed(0)} s ` +
    `(the lab keeps the last ${Math.round(s.trace_keep / 60)} min of plant time).`);
  for (const [label, v] of Object.entries(s.io)) {
    for (const node of document.querySelectorAll(`[aria-label="${CSS.escape(label)}"]`)) {
      if (node.dataset.knob !== undefined) {
        if (document.activeElement !== node && node.value !== String(v)) { node.value = String(v); node.oninput(); }
      } else if (node.getAttribute("role") === "switch" || node.classList.contains("push")) {
        showControl(node, label, v, (s.forced_labels || []).includes(label));
      }
      else if (node.dataset.state !== undefined) setAttr(node, "data-state", v ? "on" : "off");
    }
  }
  Mimic.update(s);
  if (lab.dirtyEvents) { lab.dirtyEvents = false; renderEvents(); }
  if (lab.dirtyActions) { lab.dirtyActions = false; renderActions(); }
  for (const [name, why] of Object.entries(s.trend_errors || {})) say("#trend-message", why, false);
  if (s.registers) renderRegisters(s.registers);
  if (lab.dirtyFrames) { lab.dirtyFrames = false; renderFrames(lab.frames); }
  renderWatch(s.watch || []);
  if (lab.pendingMonitor) { renderMonitor(lab.pendingMonitor); lab.pendingMonitor = null; }
  markFaultLine();
  markForced(s);
  drawTrends();
}

// A console control as the PLC sees it: a switch's position, a button pressed or not (a
// mushroom button latched). Forced, it shows the value the PLC reads, marked forced (a held
// push button otherwise shows the hold of the pointer or key on it, not the lab's echo).
function showControl(node, label, v, forced) {
  const isSwitch = node.getAttribute("role") === "switch";
  const on = forced || isSwitch || node.dataset.latch ? !!v : node.classList.contains("held");
  const attr = isSwitch ? "aria-checked" : "aria-pressed";
  if (node.getAttribute(attr) !== String(on)) node.setAttribute(attr, String(on));
  const what = isSwitch ? (on ? "on" : "off") : (on ? "pressed" : "released");
  const title = forced ? `${label} forced to ${what} (watch and force table): the PLC reads this, ` +
    `not the ${isSwitch ? "switch" : "button"}` : "";
  if (node.title !== title) node.title = title;
  const tag = node.querySelector(".forced-tag");
  if (forced && !tag) node.append(el("span", { class: "forced-tag", text: " forced" }));
  else if (!forced && tag) tag.remove();
}

function renderScript(sc) {
  let text = null;
  if (sc) {
    text = `replaying ${sc.name}: step ${sc.done} of ${sc.steps} applied` + (sc.next ? `; next ${sc.next}` : "");
    lab.scriptShown = sc.name;
  } else if (lab.scriptShown) {                 // ended (or stopped): said once
    text = `${lab.scriptShown}: finished (the console log lists each step)`;
    lab.scriptShown = null;
  }
  setProp($("#script-stop"), "disabled", !sc);
  if (text !== null && $("#script-status").textContent !== text) say("#script-status", text, true);
}

function renderEvents() {
  const list = $("#events");
  lab.events = lab.events.slice(-300);
  list.replaceChildren(...lab.events.map((e) => el("li", {
    class: e.kind === "fault_cleared" || e.kind === "out_of_range" ? "" : "fault",
    text: `t=${e.t.toFixed(2)} s ${e.kind.replace(/_/g, " ")}: ${e.detail}`,
  })));
  list.scrollTop = list.scrollHeight;
}

function renderActions() {
  const list = $("#actions");
  lab.actions = lab.actions.slice(-200);
  list.replaceChildren(...lab.actions.map((a) => el("li", { text: `t=${a.t.toFixed(2)} s ${a.text}` })));
  list.scrollTop = list.scrollHeight;
}

// ------------------------------------------------------------------ program online
// The ST of the running program, one POU at a time, with the live value of each variable use
// of the chosen instance beside it; the line a fault stopped on is marked; a fault (or a grade
// row naming file:line) opens the source there.
function buildOnline() {
  lab.pous = null;
  leaveGraded();
  $("#source").replaceChildren();
  $("#pou").replaceChildren(); $("#instance").replaceChildren();
  $("#pou").disabled = $("#instance").disabled = true;
  $("#source-open").onclick = () => loadSource();
  $("#pou").onchange = () => showPou($("#pou").value, null);
  $("#instance").onchange = () => showPou($("#pou").value, $("#instance").value);
  $("#fault-detail").onclick = () => { const f = lab.state && lab.state.plc; if (f && f.file) openSource(f.file, f.line); };
}

async function loadSource() {
  if (lab.pous) return lab.pous;
  const r = await send("source");
  lab.pous = r.pous;
  const sel = $("#pou");
  sel.replaceChildren(...lab.pous.map((p) => el("option", { value: p.name, text: `${p.name} (${p.kind.toLowerCase().replace("_", " ")}, ${p.display})` })));
  sel.disabled = false;
  if (lab.pous.length) await showPou(lab.pous[0].name, null);
  return lab.pous;
}

async function showPou(name, instance) {
  const pou = lab.pous.find((p) => p.name === name);
  if (!pou) return;
  $("#pou").value = name;
  const inst = $("#instance");
  inst.replaceChildren(...pou.instances.map((i) => el("option", { value: i, text: i })));
  inst.disabled = pou.instances.length < 2;
  instance = instance || pou.instances[0] || null;
  if (instance) inst.value = instance;
  lab.shownPou = pou;
  lab.monitorValues = {};
  const note = $("#pou-note");
  note.hidden = !pou.ladder && !pou.generated;
  note.textContent = pou.ladder ? "Ladder online: green contacts conduct, green coils are energised (power " +
    "reaches them), green wires carry power; each coil's variable and each box output's value beside it. " +
    "An edge contact (P, N) shows its variable's level (its one-scan pulse is too short to see)."
    : pou.generated ? "Drawn in OpenPLC Editor (FBD): shown as the ST it becomes, with live values." : "";
  $("#ladder").hidden = !pou.ladder;
  $("#online-note").hidden = !!pou.ladder;            // the note on the ST listing: not for a drawing
  $("#source").hidden = !!pou.ladder;
  if (pou.ladder) drawLadder(pou.ladder); else $("#ladder").replaceChildren();
  const byLine = new Map();
  for (const ref of pou.refs) { if (!byLine.has(ref[0])) byLine.set(ref[0], []); byLine.get(ref[0]).push(ref); }
  $("#source").replaceChildren(...pou.lines.map((text, i) => {
    const n = pou.line + i;
    const li = el("li", { value: String(n), id: `src-${n}`, "data-line": String(n), "data-text": text });
    let at = 0;
    for (const [, c0, c1, chain, scope, indexes] of byLine.get(n) || []) {
      const path = scope === "global" || !instance ? chain : `${instance}.${chain}`;
      // an indexed use (`Valves[i]`): its path is known once its indexes' values are (renderMonitor)
      const where = indexes ? { "data-template": path, "data-indexes": JSON.stringify(indexes) } : { "data-path": path };
      li.append(text.slice(at, c1), el("span", { class: "val", "data-chain": chain, ...where, "aria-label": `value of ${chain}` }));
      at = c1;
    }
    li.append(text.slice(at) || (at ? "" : " "));
    return li;
  }));
  markFaultLine();
  if (lab.graded) showGraded();
  await send("monitor", { pou: name, instance }).catch((e) => notice(e.message));
}

// `row`: opened from a grade row. The values beside the source are then the graded run's at
// the row's time, not the lab's live ones: the lab plays the row's scenario again on the graded
// program to that time (/api/graded) and the page shows what it read there, marked as such;
// where they cannot be had it says why and shows none (never a live value in their place).
function openSource(file, line, row) {
  if (row) enterGraded(row); else leaveGraded();
  loadSource().then((pous) => {
    const pou = pous.find((p) => p.file === file && line >= p.line && line < p.line + p.lines.length)
      || pous.find((p) => p.display === file.split("/").pop() && line >= p.line && line < p.line + p.lines.length);
    if (!pou) { notice(`${file}:${line} is not in a POU of the running program`); return; }
    return showPou(pou.name, null).then(() => {
      const li = $(`#src-${line}`);
      if (!li) return;
      for (const x of document.querySelectorAll("#source li.target-line")) x.classList.remove("target-line");
      li.classList.add("target-line");
      li.scrollIntoView({ block: "center" });
    });
  }).catch((e) => notice(e.message));
}

function enterGraded(row) {
  const t = row.time === null || row.time === undefined ? "" : `t = ${row.time.toFixed(2)} s`;
  const g = lab.graded = { row, label: `graded run (${row.scenario})` + (t ? ` at ${t}` : ""), values: null, missing: null };
  $("#source").dataset.graded = "true";
  $("#source").setAttribute("aria-label", `program source, values of the ${g.label}`);
  if (!t || !row.run) {
    g.missing = "the row names no moment of it";
    noteGraded();
    showGraded();
    return;
  }
  noteGraded(`replaying the graded run (${row.scenario}) to ${t} to show its values...`);
  post("/api/graded", { run: row.run, row: row.id }, true)
    .then((resp) => resp.json())
    .catch((e) => ({ ok: false, message: `the lab did not answer (${e.message})` }))
    .then((r) => {
      if (lab.graded !== g) return;                   // left, or another row opened, meanwhile
      if (r.ok) g.values = r.values; else g.missing = r.message;
      noteGraded();
      showGraded();
    });
  showGraded();
}

// the line above the source: whose values they are (or why there are none), and the way back
function noteGraded(pending) {
  const g = lab.graded, row = g.row;
  const note = $("#graded-note");
  const what = pending ? `Opened from grade row ${row.id}: ${pending}`
    : g.values ? `Opened from grade row ${row.id}: the values beside the source are the ${g.label}, ` +
      `not the lab's live ones.`
    : `Opened from grade row ${row.id}: the values of the ${g.label} are not available (${g.missing}); ` +
      `none are shown beside the source.`;
  const graded = row.graded ? ` ${row.graded[0].toUpperCase()}${row.graded.slice(1)}.` : "";
  note.replaceChildren(what + graded + (row.traces && row.traces.length ? " Its trace: the row's links. " : " "),
    el("button", { type: "button", class: "link", text: "Show live values", onclick: () => {
      leaveGraded();
      if (lab.shownPou) showPou(lab.shownPou.name, $("#instance").value || null);
    } }));
  note.hidden = false;
}

function leaveGraded() {
  lab.graded = null;
  $("#graded-note").hidden = true;
  $("#graded-note").replaceChildren();
  delete $("#source").dataset.graded;
  $("#source").setAttribute("aria-label", "program source");
}

// the shown POU instance's values in the graded run ("?": not available; "": none, as live)
function showGraded() {
  const g = lab.graded, pou = lab.shownPou;
  if (!g || !pou) return;
  const entry = g.values && (g.values[pou.name] || {})[$("#instance").value || ""];
  const title = entry ? `value in the ${g.label}` : g.values ? `not read in the ${g.label}`
    : `not available: ${g.missing || "replaying the graded run"}`;
  for (const span of document.querySelectorAll("#source .val")) {
    const v = entry ? entry.values[span.dataset.chain] : undefined;
    span.textContent = entry ? (v === undefined || v === null ? "" : String(v)) : "?";
    span.title = title;
    delete span.dataset.forced;                      // a force of the lab's, not of the graded run
  }
  if (pou.ladder) {
    if (entry && entry.power) renderPower(entry.power);
    else {                                           // no power shown rather than the live one
      for (const node of document.querySelectorAll("#ladder [data-from]")) node.dataset.state = "unknown";
      for (const node of document.querySelectorAll("#ladder [data-value]")) node.textContent = "?";
    }
  }
}

// An LD POU: its elements where the Editor's file puts them, wires along the stored points;
// every element and wire keyed by the output whose power it shows (renderPower).
function drawLadder(d) {
  const NS = "http://www.w3.org/2000/svg";
  const s = (tag, attrs = {}, text) => {
    const e = document.createElementNS(NS, tag);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    if (text !== undefined) e.textContent = text;
    return e;
  };
  let w = 100, h = 60;
  for (const e of d.elements) { w = Math.max(w, e.x + e.w + 90); h = Math.max(h, e.y + e.h + 30); }
  const root = s("svg", { width: w, height: h, viewBox: `0 0 ${w} ${h}` });
  for (const wire of d.wires) {
    const p = wire.points;
    let pts = p;
    if (p.length === 2 && p[0][1] !== p[1][1]) {            // two points: orthogonal, as the Editor draws
      const xm = p[1][0] + 10;
      pts = [p[1], [xm, p[1][1]], [xm, p[0][1]], p[0]];
    }
    root.append(s("polyline", { class: "wire", "data-from": wire.from, points: pts.map((q) => q.join(",")).join(" ") }));
  }
  for (const e of d.elements) {
    const g = s("g", { class: "el", "data-kind": e.kind, "data-id": String(e.id), "data-from": String(e.id) });
    const { x, y } = e, cy = y + e.h / 2;
    if (e.kind === "leftPowerRail" || e.kind === "rightPowerRail") {
      g.append(s("rect", { class: "rail", x, y, width: 4, height: e.h }));
      g.removeAttribute("data-from");
    } else if (e.kind === "contact") {
      g.setAttribute("aria-label", `contact ${e.name}`);
      g.append(s("path", { class: "sym", d: `M${x} ${cy}H${x + 10}M${x + 10} ${y}V${y + e.h}M${x + 20} ${y}V${y + e.h}M${x + 20} ${cy}H${x + e.w}` }),
        s("text", { x: x + 15, y: cy + 4, "text-anchor": "middle" }, e.mod),
        s("text", { class: "name", x: x + 15, y: y - 4, "text-anchor": "middle" }, e.name));
    } else if (e.kind === "coil") {
      g.setAttribute("aria-label", `coil ${e.name}`);
      g.append(s("path", { class: "sym", d: `M${x + 9} ${y}A12 12 0 0 0 ${x + 9} ${y + e.h}M${x + 21} ${y}A12 12 0 0 1 ${x + 21} ${y + e.h}` }),
        s("text", { x: x + 15, y: cy + 4, "text-anchor": "middle" }, e.mod),
        s("text", { class: "name", x: x + 15, y: y - 4, "text-anchor": "middle" }, e.name),
        s("text", { class: "live", "data-value": `${e.id}.var`, x: x + e.w + 4, y: cy + 4 }));
    } else if (e.kind === "block") {
      g.setAttribute("aria-label", `block ${e.name || e.type}`);
      g.removeAttribute("data-from");
      g.append(s("rect", { class: "box", x, y, width: e.w, height: e.h }),
        s("text", { x: x + e.w / 2, y: y + 12, "text-anchor": "middle", "font-weight": "bold" }, e.type),
        s("text", { class: "name", x: x + e.w / 2, y: y - 4, "text-anchor": "middle" }, e.name || ""));
      for (const [pin, rel] of e.inputs) if (rel) g.append(s("text", { x: x + 3, y: y + rel[1] + 4 }, pin));
      for (const [pin, rel] of e.outputs) {
        if (!rel) continue;
        g.append(s("text", { x: x + e.w - 3, y: y + rel[1] + 4, "text-anchor": "end" }, pin),
          s("text", { class: "live", "data-value": `${e.id}.${pin}`, x: x + e.w + 4, y: y + rel[1] - 3 }));
      }
    } else if (e.kind !== "comment") {
      g.setAttribute("aria-label", `${e.kind} ${e.name}`);
      g.append(s("rect", { class: "box", x, y, width: e.w, height: e.h, rx: 6 }),
        s("text", { class: "name", x: x + e.w / 2, y: cy + 4, "text-anchor": "middle" }, e.name),
        s("text", { class: "live", "data-value": String(e.id), x, y: y - 3 }));
    }
    root.append(g);
  }
  $("#ladder").replaceChildren(root);
}

function renderPower(power) {
  const state = (v) => v === true ? "on" : v === false ? "off" : "unknown";
  for (const node of document.querySelectorAll("#ladder [data-from]")) {
    const v = power[node.dataset.from];
    if (v !== undefined) node.dataset.state = state(v);
  }
  for (const node of document.querySelectorAll("#ladder [data-value]")) {
    const v = power[node.dataset.value];
    node.textContent = v === true ? "TRUE" : v === false ? "FALSE" : v === null || v === undefined ? "" : String(v);
  }
}

function renderMonitor(m) {
  if (!lab.shownPou || m.pou !== lab.shownPou.name || lab.graded) return;    // a graded run's moment is shown
  if (m.power && lab.shownPou.ladder) renderPower(m.power);
  for (const [chain, value] of Object.entries(m.values)) {
    for (const span of document.querySelectorAll(`#source .val[data-chain="${CSS.escape(chain)}"]`)) span.textContent = String(value);
  }
  Object.assign(lab.monitorValues, m.values);
  // an indexed use names the element its indexes' live values pick (`Main.Valves[2]`), so a
  // force of that element marks it; no value shown (out of range): no path, no mark
  for (const span of document.querySelectorAll("#source .val[data-indexes]")) {
    const items = JSON.parse(span.dataset.indexes);
    let k = 0, ok = span.textContent !== "";
    const path = span.dataset.template.replace(/\[[^\]]*\]/g, (g) => "[" + g.slice(1, -1).split(",").map(() => {
      const [text, scope] = items[k++] || [];
      const v = scope === "const" ? Number(text) : lab.monitorValues[text];
      if (!Number.isInteger(v)) ok = false;
      return String(v);
    }).join(",") + "]");
    if (ok) span.dataset.path = path;
    else { delete span.dataset.path; delete span.dataset.forced; }
  }
}

function markFaultLine() {
  const f = lab.state && lab.state.plc;
  const pou = lab.shownPou;
  const want = f && f.fault && pou && f.file === pou.file ? f.line : null;
  if (want === lab.faultLine && (want === null || $(`#src-${want}.fault-line`))) return;
  for (const x of document.querySelectorAll("#source li.fault-line")) x.classList.remove("fault-line");
  lab.faultLine = want;
  const li = want !== null ? $(`#src-${want}`) : null;
  if (li) li.classList.add("fault-line");
}

// ------------------------------------------------------------------ watch and force
// The program's variables as a tree to pick from (no path to type); the watched ones live,
// each with a force box: Force holds the value in the PLC's I/O stage every scan until
// Release. A forced variable is marked wherever the page shows it.
function buildWatch() {
  const open = $("#tree-open");
  open.onclick = async () => {
    const tree = $("#tree");
    if (!tree.hidden) { tree.hidden = true; open.setAttribute("aria-expanded", "false"); return; }
    try {
      const r = await send("tree");
      tree.replaceChildren(...r.tree.map(treeNode));
      tree.hidden = false;
      open.setAttribute("aria-expanded", "true");
    } catch (e) { say("#watch-message", e.message, false); }
  };
  $("#unforce-all").onclick = () => send("unforce").then(() => say("#watch-message", "all forces released", true))
    .catch((e) => say("#watch-message", e.message, false));
}

function treeNode(n) {
  if (n.children) {
    const d = el("details", {}, el("summary", { text: n.type ? `${n.name} : ${n.type}` : n.name }));
    d.addEventListener("toggle", () => {          // children built when opened (big arrays)
      if (d.open && d.children.length === 1) {
        d.append(el("ul", {}, ...n.children.map((c) => el("li", {}, treeNode(c)))));
        if (n.more) d.append(el("p", { class: "note", text: "more elements: watch them by index" }));
      }
    });
    return d;
  }
  return el("button", { type: "button", class: "leaf", "aria-label": `watch ${n.path}`, title: n.path,
    onclick: () => watch(lab.watched.concat([n.path])) }, `${n.name} : ${n.type}`);
}

// the list asked for is the page's until the lab answers (two quick picks both count); the
// lab's states, which come in the order it made them, say the list again after that
function watch(paths) {
  lab.watched = paths;
  lab.watchPending = (lab.watchPending || 0) + 1;
  return send("watch", { paths }).then(() => say("#watch-message", "", true))
    .catch((e) => say("#watch-message", e.message, false))
    .finally(() => { lab.watchPending--; });
}

function watchRow(path) {
  const input = el("input", { type: "text", size: "7", "aria-label": `force value of ${path}`, "data-force-of": path });
  const force = el("button", { type: "button", text: "Force", "aria-label": `force ${path}`,
    onclick: () => send("force", { path, value: input.value })
      .then(() => say("#watch-message", `${path} forced`, true)).catch((e) => say("#watch-message", e.message, false)) });
  const release = el("button", { type: "button", text: "Release", "aria-label": `release ${path}`, disabled: "",
    onclick: () => send("unforce", { path }).then(() => say("#watch-message", `${path} released`, true))
      .catch((e) => say("#watch-message", e.message, false)) });
  const remove = el("button", { type: "button", text: "x", "aria-label": `stop watching ${path}`,
    onclick: () => watch(lab.watched.filter((p) => p !== path)) });
  return el("tr", { "data-path": path }, el("td", { text: path }),
    el("td", { "aria-label": `value of ${path}` }), el("td", {}, input, force, release), el("td", {}, remove));
}

// Rows are kept while their variable is watched (what is typed in a force box, the focus and
// a click in progress survive another variable being added or removed); new ones are added.
function renderWatch(rows) {
  const body = $("#watch-table tbody");
  const want = rows.map((r) => r[0]);
  const have = [...body.children].map((tr) => tr.dataset.path);
  if (want.join("\n") !== have.join("\n")) {
    const wanted = new Set(want);
    for (const tr of [...body.children]) if (!wanted.has(tr.dataset.path)) tr.remove();
    const kept = [...body.children].map((tr) => tr.dataset.path);
    if (kept.join("\n") === want.slice(0, kept.length).join("\n")) {
      for (const path of want.slice(kept.length)) body.append(watchRow(path));
    } else {                                  // reordered: rebuilt, the rows reused
      const byPath = new Map([...body.children].map((tr) => [tr.dataset.path, tr]));
      body.replaceChildren(...want.map((path) => byPath.get(path) || watchRow(path)));
    }
  }
  rows.forEach(([path, value, forced], i) => {
    const row = body.children[i];
    if (!row) return;
    const text = (value === null ? "?" : String(value)) + (forced ? " (forced)" : "");
    if (row.children[1].textContent !== text) row.children[1].textContent = text;
    row.classList.toggle("forced", forced);
    const release = row.querySelector(`[aria-label="release ${CSS.escape(path)}"]`);
    if (release && release.disabled === forced && !document.body.classList.contains("offline")) release.disabled = !forced;
  });
}

function markForced(s) {
  const labels = new Set(s.forced_labels || []);
  for (const node of document.querySelectorAll("[data-label], #lamps [aria-label], #mimic [aria-label][data-state]")) {
    const label = node.dataset.label || node.getAttribute("aria-label");
    const forced = labels.has(label);
    if (forced !== node.classList.contains("forced")) {
      node.classList.toggle("forced", forced);
      if (forced) node.setAttribute("data-forced", "true"); else node.removeAttribute("data-forced");
    }
  }
  const forcedNames = new Set(Object.keys(s.forced || {}).map((p) => p.toUpperCase()));
  for (const name of document.querySelectorAll("#trend-list .name")) {
    const forced = forcedNames.has(name.title.toUpperCase()) || labels.has(name.title);
    name.classList.toggle("forced", forced);
  }
  for (const v of lab.graded ? [] : document.querySelectorAll("#source .val[data-path]")) {   // the program online too
    const forced = forcedNames.has(v.dataset.path.toUpperCase());
    if (forced !== (v.dataset.forced === "true")) { if (forced) v.dataset.forced = "true"; else delete v.dataset.forced; }
  }
  const n = Object.keys(s.forced || {}).length;
  setProp($("#unforce-all"), "disabled", n === 0);
  setText($("#forces"), n ? `${n} forced` : "");
}

// ------------------------------------------------------------------ the recorded program
// The frames in the PLC's frame memory, decoded (MP-9C: valves and position; TUR-10: the five
// link positions), with their pauses; the frame being executed is highlighted.
function renderFrames(f) {
  const section = $("#frames");
  section.hidden = !lab.hello || (lab.hello.stand !== "mp9c" && lab.hello.stand !== "tur10");
  const head = $("#frame-table thead"), body = $("#frame-table tbody");
  if (!f) {
    head.replaceChildren(); body.replaceChildren();
    $("#frames-status").textContent = "this program keeps no frame memory where the shipped ones do (Main.Cp)";
    return;
  }
  head.replaceChildren(...(f.rows.length ? [el("tr", {}, ...f.columns.map((c) => el("th", { text: c })))] : []));
  body.replaceChildren(...f.rows.map((r, i) => {
    const tr = el("tr", {}, ...r.map((c) => el("td", { text: c })));
    if (f.current === i + 1) { tr.className = "current"; tr.setAttribute("aria-current", "true"); }
    else if (f.done === i + 1) { tr.className = "done"; tr.title = "the frame last done"; }
    return tr;
  }));
  const n = `${f.rows.length} frame(s); `;
  $("#frames-status").textContent = !f.rows.length ? "no frame recorded (a short SB1 press in manual mode records one)"
    : f.current ? `${n}executing frame ${f.current}`
    : f.phase === "pause" ? `${n}frame ${f.done} done, its pause (then frame ${f.next})`
    : f.phase === "wait" ? `${n}frame ${f.done} done; waiting for the next SB1 press (step mode; next: frame ${f.next})`
    : f.phase === "between" ? `${n}running, between frames (next: frame ${f.next})`
    : `${n}stopped (next: frame ${f.next})`;
}

// ------------------------------------------------------------------ trends
function buildTrendList() {
  const list = $("#trend-list");
  list.replaceChildren();
  for (const name of lab.trendNames) {
    const canvas = el("canvas", { width: "600", height: "44", "aria-label": `trend of ${name}`, "data-trend": name });
    const remove = el("button", { type: "button", "aria-label": `remove trend ${name}`, text: "x",
      onclick: () => chooseTrends(lab.trendNames.filter((n) => n !== name)) });
    const unit = trendUnit(name), over = trendOverlay(name);
    const shown = name + (unit ? ` (${unit[1]})` : "") + (over ? ` + ${over}` : "");
    list.append(el("div", { class: "trend" }, el("span", { class: "name", title: name, text: shown,
      "data-shown": shown }), canvas, remove));
  }
  $("#trend-add-button").onclick = () => {
    const name = $("#trend-add").value.trim();
    if (name) chooseTrends(lab.trendNames.concat([name]));
  };
  $("#trend-add").onkeydown = (e) => { if (e.key === "Enter") $("#trend-add-button").click(); };
}

// a trend shown in a unit of its own (thermo's raw ADC in degC: [factor, unit]), and the signal
// drawn over it on the same scale (the setpoint over the temperature)
function trendUnit(name) { const u = lab.hello && lab.hello.panel.trend_units; return (u && u[name]) || null; }
function trendOverlay(name) {
  const o = lab.hello && lab.hello.panel.trend_overlays;
  return o && o[name] && lab.trendNames.includes(o[name]) ? o[name] : null;
}

function chooseTrends(names) {
  send("trends", { names }).then(() => { say("#trend-message", "", true); $("#trend-add").value = ""; })
    .catch((e) => say("#trend-message", e.message, false));
}

function setTrends(names, trends) {
  lab.trendNames = names;
  lab.trends.clear();
  for (const [name, points] of Object.entries(trends)) addPoints(name, points);
  buildTrendList();
}

function addPoints(name, points) {
  let arr = lab.trends.get(name);
  if (!arr) { arr = []; lab.trends.set(name, arr); }
  for (const p of points) {
    if (arr.length && arr[arr.length - 1][0] >= p[0]) {
      while (arr.length && arr[arr.length - 1][0] > p[0]) arr.pop();   // resent: keep the newest
      if (arr.length && arr[arr.length - 1][0] === p[0]) arr.pop();
    }
    arr.push(p);
  }
  const now = lab.state ? lab.state.t : 0;
  let cut = 0;
  while (cut < arr.length - 1 && arr[cut + 1][0] < now - lab.trendWindow) cut++;
  if (cut) arr.splice(0, cut);
}

// Each trend is drawn at the canvas's size on screen (a phone's narrow column included), the
// plot on the left, the current value in a margin of its own on the right, between the
// scale's top and bottom (no text is ever drawn over the line).
function drawTrends() {
  if (!lab.state) return;
  const span = lab.trendWindow, now = lab.state.t, from = now - span;
  const dpr = window.devicePixelRatio || 1;
  for (const canvas of document.querySelectorAll("canvas[data-trend]")) {
    const cw = Math.max(60, Math.round(canvas.clientWidth * dpr)), ch = Math.round(44 * dpr);
    if (canvas.width !== cw || canvas.height !== ch) { canvas.width = cw; canvas.height = ch; }
    const name = canvas.dataset.trend;
    const scaled = (n) => {               // a signal's points in the unit shown
      const u = trendUnit(n), k = u ? u[0] : 1;
      return (lab.trends.get(n) || []).map(([t, v]) => [t, typeof v === "number" && k !== 1 ? Math.round(v * k * 1000) / 1000 : v]);
    };
    const pts = scaled(name);
    const overName = trendOverlay(name);
    const over = overName ? scaled(overName) : [];
    const ctx = canvas.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    const w = cw / dpr, h = ch / dpr, plot = w - 64;
    ctx.clearRect(0, 0, w, h);
    if (!pts.length) continue;
    const nums = pts.concat(over).map((p) => Number(p[1])).filter((v) => Number.isFinite(v));
    let lo = Math.min(...nums), hi = Math.max(...nums);
    if (nums.every((v) => v === 0 || v === 1)) { lo = 0; hi = 1; }      // a bit: low and high
    else if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
    const x = (t) => ((Math.max(t, from) - from) / span) * plot;
    const y = (v) => h - 4 - ((v - lo) / (hi - lo)) * (h - 8);
    ctx.strokeStyle = "#1d4ed8";
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    let last = null;
    for (const [t, v] of pts) {
      const vy = y(Number(v));
      if (last === null) ctx.moveTo(x(t), vy);
      else { ctx.lineTo(x(t), last); ctx.lineTo(x(t), vy); }
      last = vy;
    }
    ctx.lineTo(plot, last);
    ctx.stroke();
    if (over.length) {                               // the overlaid signal, dashed, on the same scale
      ctx.strokeStyle = "#ea580c";
      ctx.setLineDash([4, 3]);
      ctx.beginPath();
      let lastO = null;
      for (const [t, v] of over) {
        const vy = y(Number(v));
        if (lastO === null) ctx.moveTo(x(t), vy); else { ctx.lineTo(x(t), lastO); ctx.lineTo(x(t), vy); }
        lastO = vy;
      }
      ctx.lineTo(plot, lastO);
      ctx.stroke();
      ctx.setLineDash([]);
    }
    ctx.strokeStyle = "#e5e7eb";
    ctx.beginPath(); ctx.moveTo(plot + 2, 0); ctx.lineTo(plot + 2, h); ctx.stroke();
    ctx.fillStyle = "#111";
    ctx.font = "12px sans-serif";
    const current = pts[pts.length - 1][1];
    const text = typeof current === "number" && !Number.isInteger(current) ? current.toFixed(2) : `${current}`;
    ctx.fillText(text, plot + 6, h / 2 + 4, 58);
    ctx.fillStyle = "#6b7280";                       // the scale: in the margin too, never over the line
    ctx.font = "10px sans-serif";
    ctx.fillText(`${hi}`, plot + 6, 10, 58);
    ctx.fillText(`${lo}`, plot + 6, h - 2, 58);
  }
}

// ------------------------------------------------------------------ thermo registers
function renderRegisters(regs) {
  const body = $("#register-table tbody");
  if (body.children.length !== regs.length) {
    body.replaceChildren();
    for (const r of regs) {
      const write = el("td");
      if (r.access === "read/write" && r.choices) {        // the mode: chosen by name
        const choose = el("select", { "aria-label": `new value of %MW${r.address}` },
          ...r.choices.map(([v, n]) => el("option", { value: String(v), text: `${v} ${n}` })));
        const b = el("button", { type: "button", text: "Write", "aria-label": `write %MW${r.address}` });
        b.onclick = () => send("register", { address: r.address, value: Number(choose.value) })
          .then(() => say("#register-message", `%MW${r.address} = ${choose.value} written`, true))
          .catch((e) => say("#register-message", e.message, false));
        write.append(choose, b);
      } else if (r.access === "read/write") {
        const input = el("input", { type: "text", inputmode: "numeric", "aria-label": `new value of %MW${r.address}` });
        const b = el("button", { type: "button", text: "Write", "aria-label": `write %MW${r.address}` });
        b.onclick = () => {
          const text = input.value.trim();
          // a register holds a whole number: nothing is written for an empty box or 1.5
          if (!/^[-+]?\d+$/.test(text)) {
            say("#register-message", text === "" ? `%MW${r.address}: enter a value to write (a whole number)`
              : `%MW${r.address}: '${text}' is not a whole number; nothing written`, false);
            return;
          }
          const value = Number(text);
          send("register", { address: r.address, value })
            .then(() => say("#register-message", `%MW${r.address} = ${value} written`, true))
            .catch((e) => say("#register-message", e.message, false));
        };
        input.onkeydown = (e) => { if (e.key === "Enter") b.click(); };
        write.append(input, b);
      }
      const title = [r.description, r.valid && `valid: ${r.valid}`, r.rule].filter(Boolean).join("; ");
      body.append(el("tr", {}, el("td", { text: `%MW${r.address}` }), el("td", { text: r.name, title }),
        el("td", { "aria-label": `value of %MW${r.address}`, "data-register": String(r.address) }),
        el("td", { text: r.access }), el("td", { text: r.valid }), el("td", { text: r.rule }), write));
    }
  }
  for (const r of regs) {
    const cell = body.querySelector(`[data-register="${r.address}"]`);
    const named = r.choices && r.choices.find(([v]) => v === r.value);
    if (cell) setText(cell, named ? `${r.value} (${named[1]})` : String(r.value));
  }
}

Mimic.askContour = () => send("contour");
connect();
