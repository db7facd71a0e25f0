// The mimic drawings of the three stands (SVG), moved by the plant state the server sends.
// Limit switches and valve coils drawn here carry aria-label = their label and data-state.
"use strict";

// Written only where it changed: most of the page stays as it was from one frame to the next
// (25 a second), and an unchanged write still has the browser restyle and repaint what it
// touched (measured: about a sixth of an open page's CPU). lab.js draws with these too.
function setAttr(e, name, value) {
  const v = String(value);
  if (e.getAttribute(name) !== v) e.setAttribute(name, v);
}
function setText(e, text) {
  if (e.textContent !== text) e.textContent = text;
}
function setProp(e, name, value) {       // a property: hidden, disabled, a box's value
  if (e[name] !== value) e[name] = value;
}

const Mimic = (() => {
  const NS = "http://www.w3.org/2000/svg";
  let svg = null, stand = null, parts = {}, placedLabels = new Set(), fanAngle = 0, lastT = null;

  function s(tag, attrs = {}, parent = svg) {
    const e = document.createElementNS(NS, tag);
    for (const [k, v] of Object.entries(attrs)) {
      if (k === "text") e.textContent = v; else e.setAttribute(k, v);
    }
    if (parent) parent.append(e);
    return e;
  }

  // a limit switch or coil: a labelled group whose data-state the page updates
  function indicator(kind, label, x, y, hint) {
    const g = s("g", { class: kind, role: "img", "aria-label": label, "data-state": "off", transform: `translate(${x},${y})` });
    s("title", { text: `${label}: ${hint || ""}` }, g);
    if (kind === "sensor") s("circle", { r: 7 }, g);
    else s("rect", { x: -9, y: -7, width: 18, height: 14, rx: 2 }, g);
    s("text", { class: "mimic-small", x: 10, y: 4, text: label }, g);
    placedLabels.add(label);
    return g;
  }

  function build(svgEl, standName, panel) {
    svg = svgEl;
    stand = standName;
    parts = {};
    placedLabels = new Set();
    svg.replaceChildren();
    const hints = {};
    for (const l of panel.lamps) hints[l.label] = l.hint;
    setAttr(svg, "viewBox", stand === "tur10" ? "0 0 640 545" : "0 0 640 320");
    if (stand === "mp9c") buildMp9c(hints);
    else if (stand === "tur10") buildTur10();
    else if (stand === "thermo") buildThermo();
    else if (stand === "cnc") buildCnc();
    parts.faults = s("text", { class: "fault-mark", x: 10, y: stand === "tur10" ? 540 : 312, text: "" });
  }

  // ---------------------------------------------------------------- MP-9C
  function buildMp9c(h) {
    s("text", { class: "mimic-text", x: 10, y: 18, text: "side view: lift, extension, gripper" });
    s("text", { class: "mimic-text", x: 400, y: 18, text: "top view: rotation" });
    s("rect", { class: "metal", x: 60, y: 270, width: 120, height: 14 });            // base
    parts.column = s("rect", { class: "metal", x: 100, y: 50, width: 24, height: 222 }); // lift cylinder
    parts.carriage = s("g", { id: "mimic-lift" });
    parts.liftBody = s("rect", { class: "metal", x: 92, y: -14, width: 40, height: 28, rx: 3 }, parts.carriage);
    parts.extBarrel = s("rect", { class: "metal", x: 132, y: -8, width: 90, height: 16 }, parts.carriage);
    parts.rod = s("rect", { class: "metal", x: 222, y: -4, width: 80, height: 8 }, parts.carriage);
    parts.hand = s("g", {}, parts.carriage);
    parts.gripBody = s("rect", { class: "metal", x: 0, y: -12, width: 10, height: 24 }, parts.hand);
    parts.jawTop = s("rect", { class: "metal", x: 10, y: -14, width: 22, height: 5 }, parts.hand);
    parts.jawBottom = s("rect", { class: "metal", x: 10, y: 9, width: 22, height: 5 }, parts.hand);
    // limit switches where the reed switches sit
    indicator("sensor", "SQ1", 72, 92, h.SQ1);        // lift up
    indicator("sensor", "SQ2", 72, 212, h.SQ2);       // lift down
    indicator("sensor", "SQ7", 150, 40, h.SQ7);       // extension backward
    indicator("sensor", "SQ6", 280, 40, h.SQ6);       // extension forward
    parts.sq3 = indicator("sensor", "SQ3", 0, 0, h.SQ3);   // gripper released (moves with the hand)
    // valve coils beside their cylinders
    indicator("coil", "L2", 20, 120, h.L2);
    indicator("coil", "L3", 20, 180, h.L3);
    indicator("coil", "L7", 150, 295, h.L7);
    indicator("coil", "L6", 220, 295, h.L6);
    indicator("coil", "L1", 290, 295, h.L1);
    // top view
    s("circle", { class: "metal", cx: 480, cy: 170, r: 26 });
    s("path", { d: "M 480 170 m -99 -57 A 114 114 0 0 1 579 113", fill: "none", stroke: "#cbd5e1", "stroke-dasharray": "4 4" });
    parts.topArm = s("g", { id: "mimic-rotation" });
    s("rect", { class: "metal", x: -6, y: -110, width: 12, height: 90 }, parts.topArm);
    parts.topRod = s("rect", { class: "metal", x: -3, y: -150, width: 6, height: 40 }, parts.topArm);
    indicator("sensor", "SQ4", 380, 100, h.SQ4);      // rotated left
    indicator("sensor", "SQ5", 570, 100, h.SQ5);      // rotated right
    indicator("coil", "L4", 400, 260, h.L4);
    indicator("coil", "L5", 540, 260, h.L5);
    parts.conflict = s("text", { class: "fault-mark", x: 330, y: 240, text: "" });
  }

  function updateMp9c(m) {
    const y = 92 + m.lift * 120;                    // 0 up .. 1 down
    const ext = m.extension * 60;                   // rod out
    setAttr(parts.carriage, "transform", `translate(0,${y})`);
    setAttr(parts.rod, "width", String(30 + ext));
    setAttr(parts.hand, "transform", `translate(${252 + ext},0)`);
    const open = 1 - m.gripper;
    setAttr(parts.jawTop, "y", String(-9 - 6 * open));
    setAttr(parts.jawBottom, "y", String(4 + 6 * open));
    setAttr(parts.sq3, "transform", `translate(${290 + ext},${y - 26})`);
    const angle = -30 + 60 * m.rotation;           // 0 left .. 1 right
    setAttr(parts.topArm, "transform", `translate(480,170) rotate(${angle})`);
    setAttr(parts.topRod, "y", String(-110 - 10 - ext * 0.6));
    setAttr(parts.topRod, "height", String(10 + ext * 0.6));
    const conflict = new Set(m.conflict);
    parts.column.classList.toggle("link-conflict", conflict.has("lift"));
    parts.extBarrel.classList.toggle("link-conflict", conflict.has("extension"));
    parts.topArm.firstChild.classList.toggle("link-conflict", conflict.has("rotation"));
    setText(parts.conflict, m.conflict.length ? `valve conflict: ${m.conflict.join(", ")}` : "");
  }

  // ---------------------------------------------------------------- TUR-10
  const AXES = ["shoulder", "raceme rotation", "raceme inclination", "platform rotation", "hand"];
  const RACEME = "the raceme is the robot's wrist, at the end of the forearm";
  const AXIS_TIPS = ["link 1: the shoulder lifts and lowers the upper arm", `link 2: ${RACEME}; it turns about the forearm's axis`,
    `link 3: ${RACEME}; it tilts up and down`, "link 4: the platform turns the whole arm about the vertical",
    "link 5: the hand's jaws open and close"];
  function buildTur10() {
    s("text", { class: "mimic-text", x: 10, y: 18, text: "links: position code (sensor), target of the frame (triangle), DAC reference (bar)" });
    parts.links = [];
    for (let k = 0; k < 5; k++) {
      const y0 = 30 + k * 52;
      const g = s("g", { class: "gauge", transform: `translate(0,${y0})` });
      const name = s("text", { class: "mimic-text", x: 10, y: 14, text: `${k + 1} ${AXES[k]}` }, g);
      s("title", { text: AXIS_TIPS[k] }, name);
      const track = s("rect", { x: 150, y: 4, width: 360, height: 14, fill: "#e5e7eb", stroke: "#9ca3af" }, g);
      const working = s("rect", { x: 150, y: 4, width: 0, height: 14, fill: "#d1fae5" }, g);
      const target = s("path", { id: `target-${k + 1}`, d: "M0,0 l-6,-8 h12 z", fill: "#7c3aed", visibility: "hidden",
        role: "img", "aria-label": `target of link ${k + 1}` }, g);
      const marker = s("rect", { x: 150, y: 0, width: 4, height: 22, fill: "#1d4ed8" }, g);
      const code = s("text", { id: `code-${k + 1}`, class: "mimic-small", x: 520, y: 15, text: "" }, g);
      const bus = s("text", { class: "mimic-small", x: 150, y: 46, text: "" }, g);
      s("rect", { x: 150, y: 26, width: 360, height: 8, fill: "#f1f5f9", stroke: "#cbd5e1" }, g);
      s("line", { x1: 330, x2: 330, y1: 24, y2: 36, stroke: "#64748b" }, g);
      const ref = s("rect", { x: 330, y: 26, width: 0, height: 8, fill: "#f59e0b" }, g);
      const refText = s("text", { id: `dac-${k + 1}`, class: "mimic-small", x: 520, y: 34, text: "" }, g);
      parts.links.push({ track, working, target, marker, code, ref, refText, bus });
    }
    const bus = s("g", {});
    s("title", { text: "the sensor bus: the five position sensors share one set of PLC inputs; the program enables " +
      "one sensor at a time (its read-enable output) and reads that link's code. 'enabled' lists the sensors " +
      "enabled now; two at once is bus contention" }, bus);
    parts.busLine = s("text", { class: "mimic-text", x: 10, y: 298, text: "" }, bus);
    buildRobot();
  }

  // The robot itself, side view, below the gauges: platform rotation (a dial seen from above),
  // shoulder, raceme inclination and rotation, hand; the target of the frame as a dashed ghost.
  // Each joint's angle follows its position code over the travel between the stops.
  const JOINTS = {      // axis: [angle at the lower stop, angle at the upper stop] (degrees)
    1: [-60, 60],         // shoulder: the upper arm from the vertical
    3: [-100, 100],       // raceme inclination: the forearm against the upper arm
    2: [-180, 180],       // raceme rotation: about the forearm's own axis
    4: [-135, 135],       // platform rotation: about the vertical
  };
  function arm(cls, ghost) {
    const g = s("g", { class: cls, transform: "translate(400,522)" });
    const dash = ghost ? { "stroke-dasharray": "5 4", fill: "none", stroke: "#7c3aed", "stroke-width": 2 } : { class: "metal" };
    const shoulder = s("g", {}, g);
    s("rect", { x: -9, y: -80, width: 18, height: 80, rx: 6, ...dash }, shoulder);
    const elbow = s("g", { transform: "translate(0,-80)" }, shoulder);
    s("circle", { r: 10, ...dash }, elbow);
    s("rect", { x: -7, y: -65, width: 14, height: 65, rx: 5, ...dash }, elbow);
    const wrist = s("g", { transform: "translate(0,-65)" }, elbow);
    const roll = s("ellipse", { rx: 12, ry: 5, ...dash }, wrist);
    const rollMark = s("line", { x1: 0, y1: 0, x2: 12, y2: 0, stroke: ghost ? "#7c3aed" : "#1d4ed8", "stroke-width": 2 }, wrist);
    const jawL = s("rect", { x: -10, y: -22, width: 5, height: 16, ...dash }, wrist);
    const jawR = s("rect", { x: 5, y: -22, width: 5, height: 16, ...dash }, wrist);
    return { g, shoulder, elbow, wrist, roll, rollMark, jawL, jawR };
  }
  function buildRobot() {
    s("line", { x1: 0, x2: 640, y1: 322, y2: 322, stroke: "#e5e7eb" });
    s("text", { class: "mimic-text", x: 10, y: 342, text: "robot: side view, target dashed" });
    s("rect", { class: "metal", x: 360, y: 522, width: 80, height: 12 });                 // base
    parts.robotTarget = arm("robot-target", true);
    setAttr(parts.robotTarget.g, "id", "robot-target");
    setAttr(parts.robotTarget.g, "visibility", "hidden");
    parts.robot = arm("robot", false);
    setAttr(parts.robot.shoulder, "id", "robot-shoulder");
    setAttr(parts.robot.elbow, "id", "robot-elbow");
    setAttr(parts.robot.rollMark, "id", "robot-roll");
    setAttr(parts.robot.jawL, "id", "robot-hand");
    s("text", { class: "mimic-small", x: 30, y: 370, text: "platform rotation (4)" });
    s("circle", { cx: 80, cy: 440, r: 44, fill: "#f1f5f9", stroke: "#94a3b8" });
    parts.dialTarget = s("line", { x1: 80, y1: 440, x2: 80, y2: 400, stroke: "#7c3aed", "stroke-width": 2, "stroke-dasharray": "4 3", visibility: "hidden" });
    parts.dial = s("line", { id: "robot-platform", x1: 80, y1: 440, x2: 80, y2: 400, stroke: "#1d4ed8", "stroke-width": 4 });
  }
  function frac(code, lo, hi) { return Math.max(0, Math.min(1, (code - lo) / (hi - lo))); }
  function angle(axis, code, lo, hi) { const [a, b] = JOINTS[axis]; return a + (b - a) * frac(code, lo, hi); }
  function pose(p, codes, lo, hi) {
    const a1 = angle(1, codes[0], lo, hi), a3 = angle(3, codes[2], lo, hi), a2 = angle(2, codes[1], lo, hi);
    setAttr(p.shoulder, "transform", `rotate(${a1.toFixed(2)})`);
    setAttr(p.shoulder, "data-angle", a1.toFixed(2));
    setAttr(p.elbow, "transform", `translate(0,-80) rotate(${a3.toFixed(2)})`);
    setAttr(p.elbow, "data-angle", a3.toFixed(2));
    const c = Math.cos((a2 * Math.PI) / 180);         // a roll seen from the side: the mark swings
    setAttr(p.rollMark, "x2", (12 * c).toFixed(2));
    setAttr(p.rollMark, "data-angle", a2.toFixed(2));
    const open = 4 + 10 * frac(codes[4], lo, hi);     // hand: the jaws open with its code
    setAttr(p.jawL, "x", (-open - 5).toFixed(2));
    setAttr(p.jawR, "x", open.toFixed(2));
    setAttr(p.jawL, "data-open", frac(codes[4], lo, hi).toFixed(3));
  }
  function dial(line, code, lo, hi) {
    const a = (angle(4, code, lo, hi) * Math.PI) / 180;
    setAttr(line, "x2", (80 + 40 * Math.sin(a)).toFixed(2));
    setAttr(line, "y2", (440 - 40 * Math.cos(a)).toFixed(2));
    setAttr(line, "data-angle", angle(4, code, lo, hi).toFixed(2));
  }
  function updateRobot(m) {
    const [lo, hi] = m.stops;
    const codes = m.links.map((l) => l.code);
    pose(parts.robot, codes, lo, hi);
    dial(parts.dial, codes[3], lo, hi);
    const targets = m.links.map((l) => l.target);
    const shown = targets.every((t) => t !== null && t !== undefined && t >= lo && t <= hi);
    setAttr(parts.robotTarget.g, "visibility", shown ? "visible" : "hidden");
    setAttr(parts.dialTarget, "visibility", shown ? "visible" : "hidden");
    if (shown) { pose(parts.robotTarget, targets, lo, hi); dial(parts.dialTarget, targets[3], lo, hi); }
  }

  function updateTur10(m) {
    const [lo, hi] = m.stops;
    const sx = (v) => 150 + ((v - lo) / (hi - lo)) * 360;
    m.links.forEach((l, i) => {
      const p = parts.links[i];
      setAttr(p.working, "x", String(sx(m.working[0])));
      setAttr(p.working, "width", String(sx(m.working[1]) - sx(m.working[0])));
      setAttr(p.marker, "x", String(sx(l.position) - 2));
      setAttr(p.marker, "fill", l.at_stop ? "#b91c1c" : "#1d4ed8");
      // no target (the program has none, or none set yet: outside the travel)
      if (l.target === null || l.target === undefined || l.target < lo || l.target > hi) setAttr(p.target, "visibility", "hidden");
      else {
        setAttr(p.target, "visibility", "visible");
        setAttr(p.target, "transform", `translate(${sx(l.target)},4)`);
      }
      const full = 2 * m.dac_limit;
      const w = Math.max(-180, Math.min(180, (l.reference / full) * 180));
      setAttr(p.ref, "x", String(w < 0 ? 330 + w : 330));
      setAttr(p.ref, "width", String(Math.abs(w)));
      setAttr(p.ref, "fill", l.tripped || Math.abs(l.reference) > m.dac_limit ? "#b91c1c" : "#f59e0b");
      const onBus = m.selected.includes(l.axis);
      setText(p.code, `code ${l.code}` + (l.at_stop ? " COLLISION" : ""));
      setText(p.refText, `DAC ${l.reference}` + (l.tripped ? " TRIPPED" : ""));
      setText(p.bus, onBus ? `sensor ${l.axis} on the bus` : "");
      setAttr(p.track, "stroke", onBus ? "#16a34a" : "#9ca3af");
      setAttr(p.track, "stroke-width", onBus ? "3" : "1");
    });
    const sel = m.selected.length ? m.selected.join(", ") : "none";
    setText(parts.busLine, `sensor bus: ${m.bus} (enabled: ${sel})` + (m.selected.length > 1 ? "  BUS CONTENTION" : ""));
    updateRobot(m);
  }

  // ---------------------------------------------------------------- thermo
  function buildThermo() {
    s("text", { class: "mimic-text", x: 10, y: 18, text: "heat sink with heater, fan and temperature sensor" });
    parts.sink = s("g", {});
    parts.sinkBody = s("rect", { x: 160, y: 110, width: 240, height: 40, fill: "#94a3b8", stroke: "#334155" }, parts.sink);
    for (let i = 0; i < 9; i++) s("rect", { x: 166 + i * 26, y: 150, width: 10, height: 70, fill: "#94a3b8", stroke: "#334155" }, parts.sink);
    parts.heater = s("rect", { x: 200, y: 80, width: 160, height: 30, fill: "#7f1d1d", stroke: "#111" });
    s("text", { class: "mimic-text", x: 210, y: 100, text: "heater", fill: "#fff" });
    parts.heaterText = s("text", { class: "mimic-text", x: 370, y: 100, text: "" });
    parts.temp = s("text", { class: "mimic-text", x: 420, y: 136, text: "", "font-size": "20" });
    s("circle", { cx: 410, cy: 130, r: 5, fill: "#111" });
    parts.sensorFault = s("text", { class: "fault-mark", x: 420, y: 160, text: "" });
    parts.fan = s("g", { transform: "translate(280,270)" });
    s("circle", { r: 36, fill: "#e2e8f0", stroke: "#334155" }, parts.fan);
    parts.blades = s("g", {}, parts.fan);
    for (let i = 0; i < 4; i++) s("ellipse", { rx: 8, ry: 28, fill: "#64748b", transform: `rotate(${i * 90}) translate(0,-16)` }, parts.blades);
    parts.fanText = s("text", { class: "mimic-text", x: 330, y: 275, text: "" });
    parts.mode = s("text", { id: "thermo-mode", class: "mimic-text", x: 10, y: 44, text: "" });
    parts.setpoint = s("text", { id: "thermo-setpoint", class: "mimic-text", x: 420, y: 186, text: "" });
  }
  const MODE_WORDS = { manual: "manual: %MW1 / %MW2 set the fan and the heater",
    "automatic-1": "automatic-1: the heater regulates to the setpoint", "automatic-2": "automatic-2: the fan regulates to the setpoint" };

  function updateThermo(m, t) {
    const frac = Math.max(0, Math.min(1, (m.temperature - 20) / 60));
    const r = Math.round(80 + 175 * frac), b = Math.round(200 - 170 * frac);
    setAttr(parts.sinkBody, "fill", `rgb(${r},120,${b})`);
    setAttr(parts.heater, "fill-opacity", String(0.25 + 0.75 * (m.heater_w / m.heater_max_w)));
    setText(parts.heaterText, `${m.heater_w.toFixed(1)} W (command ${m.heater_command})` + (m.faults.includes("heater_dead") ? " DEAD" : ""));
    setText(parts.temp, `${m.temperature.toFixed(1)} \u00b0C`);
    setText(parts.sensorFault, m.faults.includes("sensor_open") ? "sensor open circuit" : "");
    if (lastT !== null && t > lastT) fanAngle = (fanAngle + (m.fan_rpm / 60) * 360 * Math.min(t - lastT, 0.05)) % 360;
    setAttr(parts.blades, "transform", `rotate(${fanAngle})`);
    setText(parts.fanText, `fan ${Math.round(m.fan_rpm)} rpm (command ${m.fan_command})` + (m.faults.includes("fan_stalled") ? " STALLED" : ""));
    setText(parts.mode, m.mode_name === null || m.mode_name === undefined ? ""
      : `mode %MW0 = ${m.mode}, ${MODE_WORDS[m.mode_name] || m.mode_name}`);
    setText(parts.setpoint, m.setpoint === null || m.setpoint === undefined ? "" : `setpoint ${m.setpoint} \u00b0C`);
  }

  // ---------------------------------------------------------------- CNC
  // The X-Y table seen from above: the contour (as the PLC runs it) grey, the tool path as it
  // is cut blue, the tool a dot; beside it the frame, the contour error against its bound,
  // the drives' step counters and missed steps.
  const TIPS = {
    frame: "the part program's frame (block) the interpolator executes; evalfn: evaluation-function method, " +
      "dda: digital differential analyser, integration: digital integration",
    bound: "the largest contour error the interpolation method allows for that frame (what plclab cnc checks)",
    missed: "steps a drive did not make (it was asked faster than it can step), since the part was loaded or the faults cleared",
  };
  function buildCnc() {
    s("text", { class: "mimic-text", x: 10, y: 18, text: "X-Y table from above: contour (grey), tool path as cut (blue)" });
    s("rect", { x: 10, y: 26, width: 380, height: 284, fill: "#fff", stroke: "#e5e7eb" });
    parts.contour = s("polyline", { id: "cnc-contour", fill: "none", stroke: "#9ca3af", "stroke-width": 3 });
    parts.path = s("polyline", { id: "cnc-path", fill: "none", stroke: "#1d4ed8", "stroke-width": 1.2 });
    parts.tool = s("circle", { id: "cnc-tool", r: 4, fill: "#b91c1c" });
    const lines = ["frame", "error", "bound", "verdict", "steps", "missed", "override", "state"];
    parts.cncText = {};
    lines.forEach((k, i) => {
      const g = s("g", {});
      if (TIPS[k]) s("title", { text: TIPS[k] }, g);
      parts.cncText[k] = s("text", { id: `cnc-${k}`, class: "mimic-text", x: 400, y: 46 + i * 22, text: "" }, g);
    });
    parts.pathPts = []; parts.contourId = -1; parts.view = null;
  }
  function cncView(points) {
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    for (const [x, y] of points) { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); }
    if (!Number.isFinite(x0)) { x0 = -10; x1 = 10; y0 = -10; y1 = 10; }
    const pad = Math.max(1, 0.1 * Math.max(x1 - x0, y1 - y0));
    x0 -= pad; x1 += pad; y0 -= pad; y1 += pad;
    const k = Math.min(360 / (x1 - x0), 264 / (y1 - y0));
    return { k, x: (x) => 20 + (x - x0) * k, y: (y) => 300 - (y - y0) * k };
  }
  function setContour(c) {
    parts.contourId = c.contour_id;
    parts.view = cncView(c.contour);
    const v = parts.view;
    setAttr(parts.contour, "points", c.contour.map(([x, y]) => `${v.x(x).toFixed(1)},${v.y(y).toFixed(1)}`).join(" "));
    setAttr(parts.contour, "data-points", String(c.contour.length));
    // the path cut so far (a page opened or reloaded mid-part draws it again)
    parts.pathPts = (c.path || []).map(([x, y]) => `${v.x(x).toFixed(1)},${v.y(y).toFixed(1)}`);
    setAttr(parts.path, "points", parts.pathPts.join(" "));
    setAttr(parts.path, "data-points", String(parts.pathPts.length));
  }
  function updateCnc(m) {
    if (m.contour_id !== parts.contourId && !parts.asking) {        // a new part (or its executed form)
      parts.asking = true;
      Mimic.askContour().then(setContour).catch(() => {}).finally(() => { parts.asking = false; });
    }
    const v = parts.view || cncView([[m.x, m.y]]);
    if (m.path.length) {
      for (const p of m.path) parts.pathPts.push(`${v.x(p[0]).toFixed(1)},${v.y(p[1]).toFixed(1)}`);
      if (parts.pathPts.length > 20000) parts.pathPts.splice(0, parts.pathPts.length - 20000);
      setAttr(parts.path, "points", parts.pathPts.join(" "));
      setAttr(parts.path, "data-points", String(parts.pathPts.length));
    }
    setAttr(parts.tool, "cx", v.x(m.x).toFixed(1));
    setAttr(parts.tool, "cy", v.y(m.y).toFixed(1));
    const t = parts.cncText;
    // a frame number beyond this part's (the PLC still counts the last one's) is no frame of it
    const frame = m.frame >= 1 && m.frame <= m.frames ? String(m.frame) : m.end ? String(m.frames) : "0";
    setText(t.frame, m.part ? `frame ${frame} of ${m.frames} (${m.part}, ${m.method})` : "no part program loaded");
    const over = m.bound_mm !== null && m.error_mm > m.bound_mm + 1e-9;
    setText(t.error, `contour error ${m.error_now_mm === null ? "-" : m.error_now_mm.toFixed(4)} mm, max ${m.error_mm.toFixed(4)} mm`);
    setAttr(t.error, "fill", over ? "#b91c1c" : "#111");
    setText(t.bound, m.bound_mm === null ? "bound: -" : `bound ${m.bound_mm.toFixed(4)} mm (frame ${m.error_frame})`);
    setText(t.verdict, m.bound_mm === null ? "" : over ? "OUT OF BOUND" : "within the bound: ok");
    setAttr(t.verdict, "fill", over ? "#b91c1c" : "#15803d");
    setAttr(t.verdict, "font-weight", over ? "bold" : "normal");
    setText(t.steps, `steps X ${m.steps.X}  Y ${m.steps.Y}  Z ${m.steps.Z}`);
    const missed = m.missed.X + m.missed.Y + m.missed.Z;
    setText(t.missed, `missed steps X ${m.missed.X}  Y ${m.missed.Y}  Z ${m.missed.Z}`);
    setAttr(t.missed, "fill", missed ? "#b91c1c" : "#111");
    setText(t.override, `feed override ${m.override} %`);
    setText(t.state, m.end ? "program end" : m.cycle && m.cycle !== "idle" ? m.cycle : m.frame && m.cycle !== "idle" ? "running" : "");
  }

  function update(state) {
    if (!svg) return;
    const m = state.mimic;
    if (stand === "mp9c") updateMp9c(m);
    else if (stand === "tur10") updateTur10(m);
    else if (stand === "thermo") updateThermo(m, state.t);
    else if (stand === "cnc") updateCnc(m);
    lastT = state.t;
    setText(parts.faults, m.faults && m.faults.length ? `injected: ${m.faults.join(", ")}` : "");
  }

  const api = { build, update, placed: () => placedLabels, askContour: () => Promise.reject(new Error("no lab")) };
  return api;
})();
