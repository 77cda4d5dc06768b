// The playground: a page of the service that calls its REST API (no other origin, no build step).
// Synthesis, analysis and sweep views; the chosen design drawn to scale and animated from the
// pin positions the analysis gives at the frames drawn, with its curves at the same angles.
"use strict";

const BASE = new URL("..", location.href); // the service's root: this page is at /app/
const FRAMES = 72; // drawn frames per crank revolution
const PLOT_POINTS = 360; // the curves' angles a turn (1° apart), the exact extremes besides
const LEAST_TEXT_PX = 11; // the drawing's words are never set smaller on screen
const COLORS = ["#1f5fbf", "#d9730d", "#2e8b57", "#8e44ad", "#b0131f", "#555", "#008b8b"];
const SVGNS = "http://www.w3.org/2000/svg";
// the strokes' and dead centres' colours (literal: an exported drawing carries them)
const WORKING = "#1f5fbf", RETURN = "#d9730d", DEAD = "#b0131f";
let TYPES = {}; // type -> /v1/mechanisms record
const OBJECTIVE_TITLES = {}; // objective -> the words the service's schema gives it
const SEARCHED = new Set(); // the objectives whose value is shown beside each design (the schema's)
let current = null; // the design shown: {type, params, analysis, curves, bound}
let timer = null;
let frame = 0;
let shown = 0; // designs asked to be shown: a slower, older answer is dropped

const $ = (id) => document.getElementById(id);
const fmt = (x, d = 6) => (x === null || x === undefined ? "–" : Number(x).toPrecision(d));
// a number as a person writes it: to d significant digits, no padding zeros (180, 0.25, 1.2e-5)
const short = (x, d = 6) => (x === null || x === undefined ? "–" : String(Number(Number(x).toPrecision(d))));

async function api(path, body) {
  const init = body === undefined ? {} : {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body),
  };
  const r = await fetch(new URL(path, BASE), init);
  let data = {};
  try { data = await r.json(); } catch (e) { data = { detail: [{ loc: [], msg: `HTTP ${r.status}` }] }; }
  return { ok: r.ok, status: r.status, data };
}

function el(tag, attrs = {}, text) {
  const ns = ["svg", "g", "line", "circle", "polyline", "path", "text", "rect"].includes(tag);
  const e = ns ? document.createElementNS(SVGNS, tag) : document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

// ---- errors at the fields they name ------------------------------------------------------

function clearErrors(form) {
  for (const p of form.querySelectorAll(".error")) p.textContent = "";
  for (const f of form.querySelectorAll("[aria-invalid]")) f.removeAttribute("aria-invalid");
}

function fieldError(id, msg, formError, repeated = false) {
  const field = $(id);
  if (field && repeated) { // a condition on several fields: marked at each, said at the first
    field.setAttribute("aria-invalid", "true");
    return;
  }
  let box = $(`${id}-error`);
  if (field && !box) { // a field without its own box (advanced bounds): one after its row,
    // which keeps the grid's later rows under their labels
    let end = field;
    while (end.nextElementSibling && end.nextElementSibling.tagName !== "SPAN") end = end.nextElementSibling;
    box = el("p", { class: "error", id: `${id}-error`, role: "alert" });
    end.insertAdjacentElement("afterend", box);
  }
  if (!field || !box) {
    $(formError).textContent += (($(formError).textContent ? " " : "") + msg);
    return;
  }
  field.setAttribute("aria-invalid", "true");
  field.setAttribute("aria-describedby", box.id);
  box.textContent = box.textContent ? `${box.textContent} ${msg}` : msg;
}

function showErrors(detail, idOf, formError) {
  const said = new Set(); // a design's condition comes once per length it involves
  for (const e of detail || []) {
    fieldError(idOf(e.loc || []) || "", e.msg, formError, e.type === "invalid_design" && said.has(e.msg));
    said.add(e.msg);
  }
}

async function busy(form, run) {
  // the form's button disabled and the form marked busy while its request runs
  const button = form.querySelector("button[type=submit]");
  form.setAttribute("aria-busy", "true");
  button.disabled = true;
  try { return await run(); } finally { form.removeAttribute("aria-busy"); button.disabled = false; }
}

// ---- the synthesis view -------------------------------------------------------------------

function num(id) {
  const f = $(id);
  if (!f || f.value.trim() === "") return null;
  const x = Number(f.value);
  return Number.isFinite(x) ? x : f.value; // not a number: the service says so at the field
}

function buildTypes() {
  const box = $("types");
  for (const [t, m] of Object.entries(TYPES)) {
    const row = el("div");
    const cb = el("input", { type: "checkbox", name: "type", value: t, id: `type-${t}` });
    cb.checked = m.quick_return;
    row.append(cb, el("label", { for: `type-${t}` }, ` ${m.title}`));
    const adv = el("details", { id: `adv-${t}` });
    adv.append(el("summary", {}, `${t}: fixed parts and bounds`));
    const grid = el("div", { class: "fields" });
    grid.append(el("span", {}, "parameter"), el("span", {}, "fixed"), el("span", {}, "min"), el("span", {}, "max"));
    for (const p of m.parameters) {
      grid.append(el("span", {}, `${p.name} (${p.symbol})`));
      for (const k of ["fixed", "min", "max"]) {
        grid.append(el("input", { id: `${t}-${p.name}-${k}`, type: "number", step: "any",
          "aria-label": `${t} ${p.name} ${k}` }));
      }
    }
    adv.append(grid);
    box.append(row, adv);
  }
}

function synthRequest() {
  const stroke = num("stroke");
  const mechanisms = [];
  for (const cb of document.querySelectorAll("input[name=type]:checked")) {
    const t = cb.value;
    const spec = { type: t };
    const fixed = {}, bounds = {};
    for (const p of TYPES[t].parameters) {
      const f = num(`${t}-${p.name}-fixed`);
      const lo = num(`${t}-${p.name}-min`), hi = num(`${t}-${p.name}-max`);
      if (f !== null) fixed[p.name] = f;
      if (lo !== null || hi !== null) {
        const s = typeof stroke === "number" ? stroke : 1;
        bounds[p.name] = [lo ?? p.bounds[0] * s, hi ?? p.bounds[1] * s];
      }
    }
    if (Object.keys(fixed).length) spec.fixed = fixed;
    if (Object.keys(bounds).length) spec.bounds = bounds;
    mechanisms.push(spec);
  }
  const body = { time_ratio: num("time_ratio"), stroke, objective: $("objective").value };
  const bound = num("bound");
  if (bound !== null) body.min_transmission_angle_deg = bound;
  if (mechanisms.length) body.mechanisms = mechanisms;
  const load = loadOf("y");
  if (load) body.load = load;
  return body;
}

function synthFieldId(loc) {
  const loaded = loadFieldId("y", loc);
  if (loaded) return loaded;
  const where = loc[0] === "body" ? loc.slice(1) : loc;
  const top = { time_ratio: "time_ratio", stroke: "stroke", min_transmission_angle_deg: "bound",
    objective: "objective" };
  if (where.length === 1 && top[where[0]]) return top[where[0]];
  if (where[0] === "mechanisms" && typeof where[1] === "number") {
    const t = document.querySelectorAll("input[name=type]:checked")[where[1]]?.value;
    const kind = where.find((x) => x === "fixed" || x === "bounds");
    // [..., kind, name] or, for one end of a bound, [..., "bounds", name, 0 | 1]
    const [name, end] = where.slice(where.indexOf(kind) + 1);
    const field = kind === "fixed" ? "fixed" : end === 1 ? "max" : "min";
    if (t && kind && typeof name === "string") return `${t}-${name}-${field}`;
  }
  return null;
}

async function synthesize(choose = 0) {
  const form = $("synth-form");
  clearErrors(form);
  const body = synthRequest();
  saveState("synthesize", synthState());
  $("synth-status").textContent = "Synthesising…";
  const r = await busy(form, () => api("v1/synthesize", body));
  $("synth-status").textContent = r.ok && !r.data.complete
    ? "The time budget ran out: the notes below say what it left undone." : "";
  const tbody = $("candidates").querySelector("tbody");
  tbody.replaceChildren();
  $("refusals").replaceChildren();
  if (!r.ok) { // nothing of the last answer stays beside the errors
    showErrors(r.data.detail, synthFieldId, "form-error");
    $("front-plot").replaceChildren();
    $("detail").hidden = true;
    shown++;
    return;
  }
  const cands = r.data.candidates;
  cands.forEach((c, i) => {
    const tr = el("tr", { "data-index": i, "data-type": c.type });
    const links = el("td", { class: "lengths", "data-label": "Lengths" });
    Object.entries(c.params).forEach(([k, v], j) => { // a line breaks between lengths, not within one
      if (j) links.append(", ");
      links.append(el("span", { class: "length" }, `${k} = ${short(v, 7)}`));
    });
    // what the service says of the design beyond its lengths: its measure for the objective,
    // the limits it rests on, the free choice its family leaves
    const notes = [];
    if (SEARCHED.has(body.objective)) {
      notes.push(`${OBJECTIVE_TITLES[body.objective] || body.objective}: ${short(c.objective_value)}`);
    }
    if (c.certified) notes.push(`certified the best of its type (gap ${c.gap.toExponential(1)})`);
    else if (c.gap !== null) notes.push(`at most ${short(100 * c.gap, 3)}% above the best possible`);
    else if (c.uncertified && !cands.slice(0, i).some((b) => b.type === c.type)) {
      notes.push(`not certified the best of its type: ${c.uncertified}`);  // once per type
    }
    if (c.ranked_by !== "objective") {  // tied with the one above: which rule placed it after
      notes.push(`tied with the design above; after it by ${c.ranked_by.replaceAll("_", " ")}`);
    }
    if (c.active.length) notes.push(`at its limit: ${c.active.join(", ")}`);
    if (c.family) notes.push(c.family.relation);
    for (const n of notes) links.append(el("small", { class: "note" }, n));
    const btn = el("button", { type: "button", class: "choose",
      "aria-label": `Show candidate ${i + 1}, ${c.type}` }, "Show");
    btn.addEventListener("click", async () => {
      await choose_(cands, i, body);
      if (window.innerWidth <= 800) $("detail").scrollIntoView(); // below the table on a phone
    });
    const cell = (label, text) => el("td", { "data-label": label }, text);
    tr.append(el("td", { class: "type" }, c.type), cell("Min. transmission (°)", short(c.min_transmission_angle_deg)),
      cell(`Size (${$("y-unit").value})`, short(c.size)), links, cell("Method", c.method.replaceAll("_", " ")));
    if (body.load) tr.append(cell("Peak torque (N·m)", short(c.loads.torque.max, 5)), cell("Flywheel (kg·m²)", short(c.loads.flywheel.inertia, 4)));
    const last = el("td"); last.append(btn); tr.append(last);
    tbody.append(tr);
  });
  for (const why of r.data.infeasible) {
    $("refusals").append(el("li", { "data-type": why.type }, `${why.type}: ${why.code} — ${why.reason}`));
  }
  $("candidates").classList.toggle("with-loads", Boolean(body.load));
  frontPlot(cands, body);
  if (cands.length) choose_(cands, Math.min(choose, cands.length - 1), body);
  else $("detail").hidden = true; // only refusals: no design of the last answer stays beside them
}

function choose_(cands, i, body) {
  for (const tr of $("candidates").querySelectorAll("tbody tr")) {
    tr.classList.toggle("chosen", Number(tr.dataset.index) === i);
  }
  const c = cands[i];
  saveState("synthesize", { ...synthState(), choose: String(i) });
  return showDesign(c.type, c.params, body.min_transmission_angle_deg || 0, null, body.load || null,
    num("y-rpm"), $("y-unit").value);
}

function showUnits() {
  // each unit a select sets, where the page shows it
  for (const span of document.querySelectorAll(".unit-shown")) {
    const from = $(span.dataset.of);
    if (from && from.tagName === "SELECT") span.textContent = from.value;
  }
}

function synthState() {
  const s = { tr: $("time_ratio").value, stroke: $("stroke").value, bound: $("bound").value,
    objective: $("objective").value, unit: $("y-unit").value, rpm: $("y-rpm").value,
    types: [...document.querySelectorAll("input[name=type]:checked")].map((x) => x.value).join(",") };
  for (const f of $("types").querySelectorAll("input[type=number]")) if (f.value !== "") s[f.id] = f.value;
  return { ...s, ...loadState("y") };
}

function loadSynthState(q) {
  const set = (id, k) => { if (q.has(k)) $(id).value = q.get(k); };
  set("time_ratio", "tr"); set("stroke", "stroke"); set("bound", "bound"); set("objective", "objective");
  set("y-unit", "unit"); set("y-rpm", "rpm");
  showUnits();
  if (q.has("types")) {
    const on = new Set(q.get("types").split(","));
    for (const cb of document.querySelectorAll("input[name=type]")) cb.checked = on.has(cb.value);
  }
  for (const [k, v] of q) {
    const f = $(k);
    if (f && f.closest("#types") && f.type === "number") { f.value = v; f.closest("details").open = true; }
  }
  setLoadState("y", q);
}

// ---- the analysis and sweep views ---------------------------------------------------------

async function exampleDesign(t) {
  // a valid design of the type, from the synthesis itself (no list of types here): a stroke
  // of 100, its lengths to 6 digits as a person would type them
  const tr = TYPES[t].quick_return ? 1.6 : 1.0;
  const r = await api("v1/synthesize", { time_ratio: tr, stroke: 100, mechanisms: [{ type: t }],
    objective: "max_transmission_angle" });
  const p = r.ok && r.data.candidates.length ? r.data.candidates[0].params : {};
  return Object.fromEntries(Object.entries(p).map(([k, v]) => [k, Number(v.toPrecision(6))]));
}

async function paramInputs(prefix, t, values) {
  const box = $(`${prefix}-params`);
  box.replaceChildren();
  const v = values || await exampleDesign(t);
  for (const p of TYPES[t].parameters) {
    const id = `${prefix}-param-${p.name}`;
    box.append(el("label", { for: id }, `${p.name} (${p.symbol})`));
    const input = el("input", { id, type: "number", step: "any" });
    if (v[p.name] !== undefined) input.value = v[p.name];
    box.append(input, el("p", { class: "error", id: `${id}-error`, role: "alert" }));
  }
  if (prefix === "s") {
    const vary = $("s-vary");
    vary.replaceChildren(...TYPES[t].parameters.map((p) => el("option", { value: p.name }, p.name)));
    if (values && values.__vary) vary.value = values.__vary;
    setSweepRange();
  }
}

function designOf(prefix) {
  const t = $(`${prefix}-type`).value;
  const params = {};
  for (const p of TYPES[t].parameters) {
    const x = num(`${prefix}-param-${p.name}`);
    if (x !== null) params[p.name] = x;
  }
  return { type: t, params };
}

function designFieldId(prefix) {
  return (loc) => {
    const i = loc.indexOf("params");
    if (i >= 0 && typeof loc[i + 1] === "string") return `${prefix}-param-${loc[i + 1]}`;
    const last = loc[loc.length - 1];
    if (prefix === "s" && ["vary", "start", "stop", "points"].includes(last)) return `s-${last}`;
    return null;
  };
}

// a load's fields: [name, label, default]; the cutting zone's two ends aside, and its unit and
// the crank's speed the view's own fields (one of each a view)
const LOAD_FIELDS = [["cutting_force", "Cutting force (N)", 2000],
  ["slider_mass", "Ram and tool (kg)", 60], ["link_mass_per_length", "Links (kg/m)", 0],
  ["guide_friction", "Guide friction (μ)", 0], ["efficiency", "Drive efficiency, motor to crank", 1],
  ["speed_fluctuation", "Speed fluctuation the flywheel allows (Cs)", 0.05],
  ["flywheel_rpm", "Flywheel's shaft (rpm; blank: the crank's)", ""],
  ["flywheel_width", "Flywheel disc's width (blank: no disc)", ""],
  ["motor_rpm", "Motor speed (rpm; blank: power only)", ""],
  ["ram_incline_deg", "Working stroke above horizontal (°; 0 shaper, −90 slotter; blank: no weight)", ""]];

function loadBox(prefix) {
  // the load form of a view (ids `${prefix}-load-...`), closed: no load until opened
  const id = (k) => `${prefix}-load-${k}`;
  const fields = el("div", { class: "fields" });
  const row = (k, label, input) => fields.append(el("label", { for: id(k) }, label), input,
    el("p", { class: "error", id: `${id(k)}-error`, role: "alert" }));
  const number = (k, v) => { const x = el("input", { id: k, type: "number", step: "any" }); x.value = v; return x; };
  for (const [k, label, v] of LOAD_FIELDS.slice(0, 1)) row(k, label, number(id(k), v));
  fields.append(el("label", { for: id("cutting_zone") }, "Cuts from (fraction of the working stroke)"),
    number(id("cutting_zone"), 0.1), el("label", { for: id("cutting_zone-end") }, "to"),
    number(id("cutting_zone-end"), 0.9), el("p", { class: "error", id: `${id("cutting_zone")}-error`, role: "alert" }));
  for (const [k, label, v] of LOAD_FIELDS.slice(1)) row(k, label, number(id(k), v));
  const box = el("details", { id: `${prefix}-load` });
  box.append(el("summary", {}, "Load: torque, flywheel, joint forces (lengths in the view's unit)"), fields);
  return box;
}

function loadState(prefix) {
  // a view's load fields for its address, while its box is open (else none)
  if (!$(`${prefix}-load`).open) return {};
  return Object.fromEntries([...$(`${prefix}-load`).querySelectorAll("input, select")].map((f) => [f.id, f.value]));
}

function setLoadState(prefix, q) {
  // the load fields an address gives, the box opened for them
  for (const [k, v] of q) {
    if (k.startsWith(`${prefix}-load-`) && $(k)) { $(k).value = v; $(`${prefix}-load`).open = true; }
  }
}

function loadOf(prefix) {
  // a view's load, while its box is open (else none)
  if (!$(`${prefix}-load`).open) return null;
  // a load turns at a speed: the view's, 40 strokes a minute where none is given (shown there)
  if ($(`${prefix}-rpm`).value.trim() === "") $(`${prefix}-rpm`).value = "40";
  const load = { length_unit: $(`${prefix}-unit`).value, crank_rpm: num(`${prefix}-rpm`),
    cutting_zone: [num(`${prefix}-load-cutting_zone`), num(`${prefix}-load-cutting_zone-end`)] };
  for (const [k] of LOAD_FIELDS) load[k] = num(`${prefix}-load-${k}`);
  return load;
}

function loadFieldId(prefix, loc) {
  // the load field an error is at, or null
  const i = loc.indexOf("load");
  const own = { length_unit: `${prefix}-unit`, crank_rpm: `${prefix}-rpm` }; // the view's fields
  return i >= 0 && typeof loc[i + 1] === "string" ? own[loc[i + 1]] || `${prefix}-load-${loc[i + 1]}` : null;
}

function analysisFieldId(loc) {
  if (loc[loc.length - 1] === "crank_speed") return "a-rpm";
  return loadFieldId("a", loc) ?? designFieldId("a")(loc);
}

async function analyzeView() {
  const form = $("analyze-form");
  clearErrors(form);
  const d = designOf("a");
  const load = loadOf("a"); // first: it gives the speed its default
  saveState("analyze", { type: d.type, ...d.params, __unit: $("a-unit").value, __rpm: $("a-rpm").value,
    ...loadState("a") });
  await busy(form, () => showDesign(d.type, d.params, 0,
    (detail) => showErrors(detail, analysisFieldId, "a-form-error"), load, num("a-rpm"), $("a-unit").value));
}

function setSweepRange() {
  const v = num(`s-param-${$("s-vary").value}`);
  if (typeof v === "number" && v !== 0) {
    $("s-start").value = Number((0.5 * v).toPrecision(6));
    $("s-stop").value = Number((1.5 * v).toPrecision(6));
  }
}

async function sweepView() {
  const form = $("sweep-form");
  clearErrors(form);
  const d = designOf("s");
  const body = { mechanism: d, vary: $("s-vary").value, start: num("s-start"), stop: num("s-stop"),
    points: num("s-points") };
  saveState("sweep", { type: d.type, ...d.params, __vary: body.vary, __start: $("s-start").value,
    __stop: $("s-stop").value, __points: $("s-points").value, __unit: $("s-unit").value });
  const r = await busy(form, () => api("v1/sweep", body));
  const svg = $("sweep-plot");
  svg.replaceChildren();
  $("s-status").textContent = "";
  if (!r.ok) { showErrors(r.data.detail, designFieldId("s"), "s-form-error"); return; }
  const s = r.data;
  $("s-status").textContent = s.complete ? "" : !s.values.length
    ? "The time budget ran out before any value was analysed."
    : `The time budget ran out: the sweep ends at ${s.vary} = ${fmt(s.values.at(-1), 7)}.`;
  const here = num(`s-param-${s.vary}`);
  plot(svg, s.values, [
    { ys: s.time_ratio, color: COLORS[0], label: "time ratio" },
    { ys: s.min_transmission_angle_deg, color: COLORS[1], label: "min. transmission (°)", right: true },
  ], { xlabel: `${s.vary} (${$("s-unit").value})`, ylabel: "time ratio (slow / quick)",
    ylabel2: "min. transmission angle (°)", shade: s.valid_interval,
    mark: typeof here === "number" ? { x: here, label: "this design" } : undefined });
}

// ---- one design: drawing, animation, curves -------------------------------------------------

function pinsOf(curves) {
  // {pin: {x: [...], y: [...]}} at the curve's angles
  return curves.pins || {};
}

async function showDesign(type, params, bound, onError, load = null, rpm = null, unit = "mm") {
  // the curves at the load's crank speed, else at rpm strokes a minute, else per unit ω; the
  // lengths in unit
  const mine = ++shown;
  const loaded = load ? { load } : rpm !== null ? { crank_speed: typeof rpm === "number" ? (rpm * Math.PI) / 30 : rpm } : {};
  const summary = await api("v1/analyze", { mechanism: { type, params }, include: ["motion", "sensitivities"], ...loaded });
  if (mine !== shown) return;
  if (!summary.ok) {
    if (onError) onError(summary.data.detail);
    $("detail").hidden = true;
    return;
  }
  const a = summary.data;
  const tmin = a.extremes.min.crank_angle_deg, tmax = a.extremes.max.crank_angle_deg;
  // the frames drawn, the dead centres, then the plots' angles: every degree, and where the
  // acceleration peaks and the torque is extreme (so the plots reach the exact extremes the
  // analysis found)
  const peaks = a.motion.peak_acceleration;
  const extra = [peaks.working_stroke_at_deg, peaks.return_stroke_at_deg].concat(
    a.loads ? [a.loads.torque.max_at_deg, a.loads.torque.min_at_deg] : []);
  const angles = [...Array(FRAMES).keys()].map((k) => (k * 360) / FRAMES).concat([tmin, tmax],
    [...Array(PLOT_POINTS).keys()], extra);
  const [r, drawn] = await Promise.all([
    api("v1/analyze", { mechanism: { type, params }, crank_angles_deg: angles,
      include: (TYPES[type].drawing.length ? ["pins"] : []).concat(load ? ["forces"] : []), ...loaded }),
    api("v1/export", { mechanism: { type, params }, format: "json" }), // its symbols' shapes
  ]);
  if (mine !== shown) return;
  if (!r.ok) { if (onError) onError(r.data.detail); $("detail").hidden = true; return; }
  current = { type, params: a.params, analysis: a, curves: r.data.curves, bound, load,
    rpm: load ? load.crank_rpm : rpm, unit,
    sketch: drawn.ok ? drawn.data : null };
  for (const span of document.querySelectorAll(".unit-shown[data-of=design-unit]")) span.textContent = unit;
  $("detail").hidden = false;
  $("detail-title").textContent = `${TYPES[type].title}`;
  $("detail-summary").textContent = `time ratio ${fmt(a.time_ratio, 8)}, stroke ${fmt(a.stroke, 8)}, ` +
    `minimum transmission angle ${fmt(a.transmission.min_deg, 6)}°` +
    (a.conditioning.flags.length ? ` (${a.conditioning.flags.join(", ")})` : "");
  drawLinkage();
  curvePlots();
  loadsView();
  sensitivitiesView();
  setFrame(0);
  play(true);
  $("detail").dataset.shown = String(mine); // drawn: for tests and tools that wait on it
}

function phase(theta) {
  // "working" or "return" for a crank angle, from the analysis's strokes
  const a = current.analysis;
  const start = a.working_stroke.direction > 0 ? a.extremes.min.crank_angle_deg : a.extremes.max.crank_angle_deg;
  const into = (((theta - start) % 360) + 360) % 360;
  return into < a.working_stroke.crank_angle_deg ? "working" : "return";
}

function drawLinkage() {
  const svg = $("linkage");
  svg.replaceChildren();
  const pins = pinsOf(current.curves);
  const names = Object.keys(pins);
  if (!names.length) return;
  let xs = [], ys = [];
  for (const n of names) { xs = xs.concat(pins[n].x); ys = ys.concat(pins[n].y); }
  const sk = current.sketch && current.sketch.sketch;
  if (sk) for (const [x, y] of [...sk.guide.flat(), ...sk.dimension, sk.label_at]) { xs.push(x); ys.push(y); }
  const xmin = Math.min(...xs), xmax = Math.max(...xs), ymin = Math.min(...ys), ymax = Math.max(...ys);
  const pad = 0.08 * Math.max(xmax - xmin, ymax - ymin, 1e-12);
  svg.setAttribute("viewBox", `${xmin - pad} ${-(ymax + pad)} ${xmax - xmin + 2 * pad} ${ymax - ymin + 2 * pad}`);
  svg.setAttribute("preserveAspectRatio", "xMidYMid meet");
  // the words at the drawing's size, but never smaller on screen than LEAST_TEXT_PX (a phone)
  const box = svg.getBoundingClientRect();
  const perUnit = Math.min(box.width / (xmax - xmin + 2 * pad), box.height / (ymax - ymin + 2 * pad)) || 1;
  const textSize = Math.max(sk ? sk.text_height : pad * 0.3, LEAST_TEXT_PX / perUnit);
  const world = el("g", { transform: "scale(1,-1)", id: "world" });
  svg.append(world);
  const drawing = TYPES[current.type].drawing;
  const crank = drawing.find((d) => d[0] === "crank");
  const stroke = { "vector-effect": "non-scaling-stroke" };
  // the crank pin's path, coloured by stroke, and the dead centres
  if (crank) {
    const [, c, p] = crank;
    for (let k = 0; k < FRAMES; k++) {
      const k2 = (k + 1) % FRAMES, th = (k * 360) / FRAMES;
      world.append(el("line", { ...stroke, class: `path ${phase(th + 180 / FRAMES)}`,
        x1: pins[p].x[k], y1: pins[p].y[k], x2: pins[p].x[k2], y2: pins[p].y[k2],
        stroke: phase(th + 180 / FRAMES) === "working" ? WORKING : RETURN, "stroke-width": 3 }));
    }
    for (const k of [FRAMES, FRAMES + 1]) {
      world.append(el("line", { ...stroke, class: "dead-centre", x1: pins[c].x[k], y1: pins[c].y[k],
        x2: pins[p].x[k], y2: pins[p].y[k], stroke: DEAD, "stroke-dasharray": "4 3", "stroke-width": 1.5 }));
    }
  }
  const slider = names[names.length - 1]; // the slider's pin is the drawing's last
  for (const k of [FRAMES, FRAMES + 1]) {
    world.append(el("circle", { class: "dead-centre", cx: pins[slider].x[k], cy: pins[slider].y[k],
      r: pad * 0.12, fill: DEAD }));
  }
  world.append(el("polyline", { ...stroke, class: "slider-path", fill: "none", stroke: "#bbb",
    points: pins[slider].x.slice(0, FRAMES).map((x, k) => `${x},${pins[slider].y[k]}`).join(" ") }));
  if (sk) { // the frame's symbols, the service's shapes: guide, fixed pivots, stroke
    const pts = (ps) => ps.map(([x, y]) => `${x},${y}`).join(" ");
    for (const [[x1, y1], [x2, y2]] of [...sk.guide, ...sk.hatch]) {
      world.append(el("line", { ...stroke, class: "frame", x1, y1, x2, y2, stroke: "#555" }));
    }
    for (const t of sk.ground) world.append(el("polygon", { ...stroke, class: "ground", points: pts(t), fill: "#bbb", stroke: "#333" }));
    const [[d1x, d1y], [d2x, d2y]] = sk.dimension;
    world.append(el("line", { ...stroke, class: "dimension", x1: d1x, y1: d1y, x2: d2x, y2: d2y, stroke: "#333" }));
    svg.append(el("text", { class: "dimension", x: sk.label_at[0], y: -sk.label_at[1], "text-anchor": "middle",
      style: `font-size:${textSize}px` }, sk.label));
    // the ram's block and the slot it carries across its path (a slot drive's, a yoke's): one body
    const ram = el("g", { id: "block" });
    for (const [[x1, y1], [x2, y2]] of current.sketch.drawing.yokes) {
      ram.append(el("line", { ...stroke, class: "yoke", x1, y1, x2, y2, stroke: "#bbb", "stroke-width": 7 }));
    }
    ram.append(el("polygon", { ...stroke, class: "slider", points: pts(sk.block), fill: "#ddd", stroke: "#333" }));
    world.append(ram);
  }
  const moving = el("g", { id: "moving" });
  for (const names of (current.sketch && current.sketch.drawing.slots) || []) {
    moving.append(el("line", { ...stroke, class: "slot", "data-pins": names.join(" "), stroke: "#bbb", "stroke-width": 7 }));
  }
  for (const [name, a, b] of drawing) {
    if (current.params[name] === 0) continue; // a part left out (a slot drive)
    moving.append(el("line", { ...stroke, class: "member", "data-name": name, "data-from": a, "data-to": b,
      stroke: name === "crank" ? WORKING : "#333", "stroke-width": 3, "stroke-linecap": "round" }));
  }
  for (const n of names) {
    moving.append(el("circle", { class: "pin", "data-name": n, r: pad * 0.08, fill: "#fff",
      stroke: "#333", ...stroke }));
  }
  world.append(moving);
  for (const n of names) { // upright: outside the flipped group, at (x, −y)
    svg.append(el("text", { class: "pin-label", "data-name": n, style: `font-size:${textSize}px` }, n));
  }
}

function setFrame(k) {
  frame = ((k % FRAMES) + FRAMES) % FRAMES;
  $("angle").value = frame;
  const th = (frame * 360) / FRAMES;
  $("angle-out").textContent = `${th}° (${phase(th)} stroke)`;
  const pins = pinsOf(current.curves);
  for (const line of document.querySelectorAll("#linkage line.member")) {
    const a = pins[line.dataset.from], b = pins[line.dataset.to];
    line.setAttribute("x1", a.x[frame]); line.setAttribute("y1", a.y[frame]);
    line.setAttribute("x2", b.x[frame]); line.setAttribute("y2", b.y[frame]);
    if (line.dataset.name === "crank") line.setAttribute("stroke", phase(th) === "working" ? WORKING : RETURN);
  }
  for (const c of document.querySelectorAll("#linkage circle.pin")) {
    const p = pins[c.dataset.name];
    c.setAttribute("cx", p.x[frame]); c.setAttribute("cy", p.y[frame]);
  }
  const r = 1.5 * Number(document.querySelector("#linkage circle.pin")?.getAttribute("r") || 0);
  for (const t of document.querySelectorAll("#linkage text.pin-label")) {
    const p = pins[t.dataset.name];
    t.setAttribute("x", p.x[frame] + r); t.setAttribute("y", -p.y[frame] - r);
  }
  for (const line of document.querySelectorAll("#linkage line.slot")) { // to the farther pin
    const [a, b, c] = line.dataset.pins.split(" ").map((n) => [pins[n].x[frame], pins[n].y[frame]]);
    const end = Math.hypot(b[0] - a[0], b[1] - a[1]) > Math.hypot(c[0] - a[0], c[1] - a[1]) ? b : c;
    line.setAttribute("x1", a[0]); line.setAttribute("y1", a[1]); line.setAttribute("x2", end[0]); line.setAttribute("y2", end[1]);
  }
  const block = $("block");
  if (block && current.sketch) { // the ram's block, moved with the ram's pin
    const d = current.sketch.drawing, ram = pins[d.ram], at = d.pins[d.ram];
    block.setAttribute("transform", `translate(${ram.x[frame] - at[0]},${ram.y[frame] - at[1]})`);
  }
  for (const cur of document.querySelectorAll("#detail .cursor")) {
    cur.setAttribute("x1", cur.dataset.scale * th + Number(cur.dataset.offset));
    cur.setAttribute("x2", cur.getAttribute("x1"));
  }
}

function play(on) {
  clearInterval(timer);
  timer = on ? setInterval(() => setFrame(frame + 1), 80) : null;
  $("play").textContent = on ? "Pause" : "Play";
  $("play").setAttribute("aria-pressed", String(on));
}

function sortedCurves() {
  // the curves past the animation's frames (the dead centres, every degree, the torque's
  // extremes), by crank angle in [0, 360): what the plots draw
  const c = current.curves;
  const idx = [...c.crank_angle_deg.keys()].slice(FRAMES)
    .map((k) => [((c.crank_angle_deg[k] % 360) + 360) % 360, k]).sort((p, q) => p[0] - q[0]);
  const pick = (v) => (v ? idx.map(([, k]) => v[k]) : null);
  const forces = c.forces ? Object.fromEntries(Object.entries(c.forces).map(([k, v]) => [k, pick(v)])) : null;
  return { th: idx.map(([x]) => x), position: pick(c.position), velocity: pick(c.velocity),
    acceleration: pick(c.acceleration), transmission: pick(c.transmission_deg), torque: pick(c.torque), forces };
}

function crankAxis() {
  // what every plot against the crank angle shares: its axis, the dead centres, the strokes, the cursor
  const e = current.analysis.extremes;
  return { xlabel: "crank angle (°)", xticks: [0, 90, 180, 270, 360],
    vlines: [e.min.crank_angle_deg, e.max.crank_angle_deg], cursor: true, phases: true };
}

function curvePlots() {
  const c = sortedCurves();
  const common = crankAxis();
  const unit = current.unit;
  const rate = current.rpm ? `${unit}/s` : `${unit}/rad`, rate2 = current.rpm ? `${unit}/s²` : `${unit}/rad²`;
  const at = current.rpm ? `at ${current.rpm} rpm` : "per radian of crank (ω = 1)";
  plot($("plot-position"), c.th, [{ ys: c.position, color: COLORS[0], label: "position" }], { ...common, ylabel: `position (${unit})` });
  plot($("plot-velocity"), c.th, [{ ys: c.velocity, color: COLORS[0], label: `velocity ${at}` }],
    { ...common, ylabel: `velocity (${rate})` });
  plot($("plot-acceleration"), c.th, [{ ys: c.acceleration, color: COLORS[0], label: `acceleration ${at}` }],
    { ...common, ylabel: `acceleration (${rate2})` });
  plot($("plot-transmission"), c.th, [{ ys: c.transmission, color: COLORS[0], label: "transmission angle" }],
    { ...common, ylabel: "transmission angle (°)", hlines: current.bound > 0 ? [{ y: current.bound, label: `bound ${current.bound}°` }] : [] });
}

function loadsView() {
  // with a load: its figures as a small table, the torque over the turn against its mean (the
  // areas between them shaded: above the mean the flywheel gives, below it takes), and the
  // joints' and the guide's forces
  const l = current.analysis.loads;
  $("loads").hidden = !l;
  if (!l) return;
  const n = (x, d = 4) => short(x, d);
  const top = Object.entries(l.joints).reduce((a, b) => (b[1].max > a[1].max ? b : a));
  const rows = [
    ["Crank torque", `${n(l.torque.min)} … ${n(l.torque.max)} N·m, mean ${n(l.torque.mean)}, rms ${n(l.torque.rms)}`],
    ["Power", `mean ${n(l.power.mean)} W, peak ${n(l.power.peak)} W`],
    ["Motor", `${n(l.power.rated)} W` + (l.power.motor_torque == null ? "" : `, ${n(l.power.motor_torque)} N·m at its speed`)],
    ["Flywheel", `energy swing ${n(l.flywheel.energy)} J; inertia ${n(l.flywheel.inertia)} kg·m² ` +
      `on a shaft at ${short(l.flywheel.rpm, 6)} rpm` +
      (l.flywheel.disc_diameter == null ? "" : `, a steel disc ${n(l.flywheel.disc_diameter)} ${current.unit} across`)],
    ["Largest joint force", `${n(top[1].max)} N at ${top[0]}`],
    ["Guide", `${n(l.guide.max)} N`],
  ];
  $("loads-summary").tBodies[0].replaceChildren(...rows.map(([k, v]) => {
    const tr = el("tr"); tr.append(el("th", { scope: "row" }, k), el("td", {}, v)); return tr;
  }));
  const c = sortedCurves();
  const common = crankAxis();
  plot($("plot-torque"), c.th, [{ ys: c.torque, color: COLORS[0], label: "crank torque" }],
    { ...common, ylabel: "torque (N·m)", fillTo: l.torque.mean, hlines: [{ y: l.torque.mean, label: `mean ${n(l.torque.mean)}` }] });
  const forces = Object.entries(c.forces || {});
  plot($("plot-forces"), c.th, forces.map(([k, ys], i) => ({ ys, color: COLORS[i % COLORS.length], label: k })),
    { ...common, ylabel: "force (N)", shared: true });
}

function sensitivitiesView() {
  // how each figure moves with each part (per one of the design's unit)
  const s = current.analysis.sensitivities;
  const mu = s.min_transmission_angle_deg || {};
  $("sensitivities").tBodies[0].replaceChildren(...Object.keys(s.time_ratio).map((k) => {
    const tr = el("tr");
    tr.append(el("th", { scope: "row" }, k), el("td", {}, short(s.time_ratio[k], 4)),
      el("td", {}, short(s.stroke[k], 4)), el("td", {}, k in mu ? short(mu[k], 4) : "–"));
    return tr;
  }));
}

function ticks(lo, hi, n = 4) {
  // about n round numbers between lo and hi
  if (!(hi > lo)) return [lo];
  const raw = (hi - lo) / n, p = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * p).find((st) => st >= raw);
  const out = [];
  for (let x = Math.ceil(lo / step) * step; x <= hi + step * 1e-9; x += step) out.push(Math.abs(x) < step * 1e-9 ? 0 : x);
  return out;
}

// A small line plot in an SVG: series against xs, on one scale (`shared`) or each its own (a
// second scale on the right for `right` series); axis titles with their units (`xlabel`,
// `ylabel`, `ylabel2` for the right), the legend above the plotting area; dashed vertical
// lines, horizontal lines, shaded x intervals, a cursor.
function plot(svg, xs, series, opts = {}) {
  svg.replaceChildren();
  const right = series.some((s) => s.right);
  const W = 400, H = 190, L = 58, R = right ? 58 : 14, T = 22, B = 34;
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  const finite = (v) => v.filter((y) => y !== null && Number.isFinite(y));
  const range = (v) => { const f = finite(v); const lo = Math.min(...f), hi = Math.max(...f); return hi > lo ? [lo, hi] : [lo - 1, hi + 1]; };
  const [x0, x1] = range(xs);
  const sx = (x) => L + ((x - x0) / (x1 - x0)) * (W - L - R);
  const extra = (opts.hlines || []).map((h) => h.y);
  const shared = opts.shared ? series.flatMap((s) => s.ys) : null;
  const bounds = (s) => range((shared || s.ys).concat(extra));
  const scale = (s) => { const [a, b] = bounds(s); return (y) => H - B - ((y - a) / (b - a)) * (H - T - B); };
  for (const [lo, hi] of opts.shade || []) {
    svg.append(el("rect", { class: "valid", x: sx(lo), y: T, width: Math.max(sx(hi) - sx(lo), 1), height: H - T - B, fill: "#e8f3e8" }));
  }
  if (opts.phases && current) {
    for (let k = 0; k < xs.length; k++) {
      svg.append(el("rect", { x: sx(xs[k]), y: H - B, width: (W - L - R) / xs.length + 0.5, height: 4,
        fill: phase(xs[k]) === "return" ? RETURN : WORKING }));
    }
  }
  svg.append(el("line", { x1: L, y1: H - B, x2: W - R, y2: H - B, stroke: "#999" }));
  svg.append(el("line", { x1: L, y1: T, x2: L, y2: H - B, stroke: "#999" }));
  for (const x of opts.xticks || ticks(x0, x1)) { // grid lines and their numbers
    svg.append(el("line", { class: "grid", x1: sx(x), x2: sx(x), y1: T, y2: H - B, stroke: "#eee" }));
    svg.append(el("text", { class: "tick", x: sx(x), y: H - B + 14, "text-anchor": "middle" }, short(x)));
  }
  axisTitles(svg, { W, H, L, R, T, B }, opts.xlabel, opts.ylabel, opts.ylabel2);
  legend(svg, L, series.map((s) => [s.label, s.color]));
  series.forEach((s, i) => {
    const sy = scale(s);
    if (!shared || i === 0) {
      for (const y of ticks(...bounds(s))) {
        if (i === 0) svg.append(el("line", { class: "grid", x1: L, x2: W - R, y1: sy(y), y2: sy(y), stroke: "#eee" }));
        svg.append(el("text", { class: "tick", x: s.right ? W - R + 3 : L - 3, y: sy(y) + 4,
          "text-anchor": s.right ? "start" : "end", style: `fill:${shared ? "#666" : s.color}` }, short(y)));
      }
    }
    if (opts.fillTo !== undefined) { // the areas between the series and a level, by sign
      for (let k = 0; k + 1 < xs.length; k++) {
        const y = (s.ys[k] + s.ys[k + 1]) / 2;
        svg.append(el("rect", { class: y >= opts.fillTo ? "gives" : "takes", x: sx(xs[k]),
          y: Math.min(sy(y), sy(opts.fillTo)), width: sx(xs[k + 1]) - sx(xs[k]),
          height: Math.abs(sy(y) - sy(opts.fillTo)), fill: y >= opts.fillTo ? "#f6d5d5" : "#d5ecd9" }));
      }
    }
    const pts = [];
    s.ys.forEach((y, k) => { if (y !== null && Number.isFinite(y)) pts.push(`${sx(xs[k])},${sy(y)}`); });
    const drawn = finite(s.ys);
    svg.append(el("polyline", { points: pts.join(" "), fill: "none", stroke: s.color, "stroke-width": 1.5,
      class: "series", "data-max": Math.max(...drawn), "data-min": Math.min(...drawn) }));
    for (const h of opts.hlines || []) {
      svg.append(el("line", { class: "bound", x1: L, x2: W - R, y1: sy(h.y), y2: sy(h.y), stroke: DEAD, "stroke-dasharray": "5 3" }));
      svg.append(el("text", { x: W - R - 70, y: sy(h.y) - 3 }, h.label));
    }
  });
  for (const v of opts.vlines || []) {
    svg.append(el("line", { class: "dead-centre", x1: sx(v), x2: sx(v), y1: T, y2: H - B, stroke: DEAD, "stroke-dasharray": "3 3" }));
  }
  if (opts.mark !== undefined && opts.mark.x >= x0 && opts.mark.x <= x1) { // a value of x to point out (the design a sweep varies)
    svg.append(el("line", { class: "mark", x1: sx(opts.mark.x), x2: sx(opts.mark.x), y1: T, y2: H - B, stroke: "#333", "stroke-width": 1.5 }));
    svg.append(el("text", { class: "mark-label", x: sx(opts.mark.x) + 3, y: T + 11 }, opts.mark.label));
  }
  if (opts.cursor) {
    svg.append(el("line", { class: "cursor", x1: L, x2: L, y1: T, y2: H - B, stroke: "#333",
      "data-scale": (W - L - R) / (x1 - x0), "data-offset": L - (x0 * (W - L - R)) / (x1 - x0) }));
  }
}

function frontPlot(cands, body) {
  // each type's candidates, size against the least transmission angle; a point shows its design
  const svg = $("front-plot");
  svg.replaceChildren();
  if (!cands.length) return;
  const types = [...new Set(cands.map((c) => c.type))];
  const W = 400, H = 200, L = 58, R = 14, T = 22, B = 34;
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  const span = (v) => { const lo = Math.min(...v), hi = Math.max(...v); return hi > lo ? [lo, hi] : [lo - 1, hi + 1]; };
  const xt = ticks(...span(cands.map((c) => c.size))), yt = ticks(...span(cands.map((c) => c.min_transmission_angle_deg)));
  const [x0, x1] = [Math.min(xt[0], ...cands.map((c) => c.size)), Math.max(xt.at(-1), ...cands.map((c) => c.size))];
  const [y0, y1] = [Math.min(yt[0], ...cands.map((c) => c.min_transmission_angle_deg)),
    Math.max(yt.at(-1), ...cands.map((c) => c.min_transmission_angle_deg))];
  const pad = 0.04;
  const sx = (x) => L + (pad + (1 - 2 * pad) * (x - x0) / (x1 - x0 || 1)) * (W - L - R);
  const sy = (y) => H - B - (pad + (1 - 2 * pad) * (y - y0) / (y1 - y0 || 1)) * (H - T - B);
  for (const x of xt) {
    svg.append(el("line", { class: "grid", x1: sx(x), x2: sx(x), y1: T, y2: H - B, stroke: "#eee" }));
    svg.append(el("text", { class: "tick", x: sx(x), y: H - B + 14, "text-anchor": "middle" }, short(x)));
  }
  for (const y of yt) {
    svg.append(el("line", { class: "grid", x1: L, x2: W - R, y1: sy(y), y2: sy(y), stroke: "#eee" }));
    svg.append(el("text", { class: "tick", x: L - 3, y: sy(y) + 4, "text-anchor": "end" }, short(y)));
  }
  svg.append(el("line", { x1: L, y1: H - B, x2: W - R, y2: H - B, stroke: "#999" }), el("line", { x1: L, y1: T, x2: L, y2: H - B, stroke: "#999" }));
  axisTitles(svg, { W, H, L, R, T, B }, `size (Σ lengths, ${$("y-unit").value})`, "min. transmission angle (°)");
  legend(svg, L, types.map((t, i) => [t, COLORS[i % COLORS.length]]));
  types.forEach((t, i) => {
    const colour = COLORS[i % COLORS.length];
    const mine = cands.map((c, k) => [c, k]).filter(([c]) => c.type === t);
    svg.append(el("polyline", { fill: "none", stroke: colour, "stroke-width": 1,
      points: mine.map(([c]) => `${sx(c.size)},${sy(c.min_transmission_angle_deg)}`).join(" ") }));
    for (const [c, k] of mine) {
      const dot = el("circle", { cx: sx(c.size), cy: sy(c.min_transmission_angle_deg), r: 4, fill: colour, "data-index": k });
      dot.addEventListener("click", () => choose_(cands, k, body));
      svg.append(dot);
    }
  });
}

function axisTitles(svg, { W, H, L, R, T, B }, x, y, y2) {
  // a plot's axis titles (each with its unit): under the x axis, beside the y axes
  const title = (text, tx, ty, turn) => svg.append(el("text", { class: "axis-title", x: tx, y: ty, "text-anchor": "middle",
    ...(turn ? { transform: `rotate(${turn} ${tx} ${ty})` } : {}) }, text));
  if (x) title(x, (L + W - R) / 2, H - 3);
  if (y) title(y, 11, (T + H - B) / 2, -90);
  if (y2) title(y2, W - 6, (T + H - B) / 2, 90);
}

function legend(svg, L, items) {
  // [label, colour] in a row above the plotting area, each in its colour (inline: the page's
  // text colour would override it)
  let at = L;
  for (const [label, colour] of items) {
    svg.append(el("text", { class: "legend", x: at, y: 13, style: `fill:${colour}` }, label));
    at += 7 * label.length + 12;
  }
}

// ---- export ------------------------------------------------------------------------------------

function download(name, type, text) {
  const a = el("a", { href: URL.createObjectURL(new Blob([text], { type })), download: name });
  document.body.append(a); a.click(); a.remove();
}

async function exportDrawing(format) {
  // the service's drawing at the frame shown: SVG in true size, DXF for CAD, a GIF of a turn
  if (!current) return;
  const body = { mechanism: { type: current.type, params: current.params }, format,
    crank_angle_deg: (frame * 360) / FRAMES, length_unit: current.unit, paths: true };
  const r = await fetch(new URL("v1/export", BASE), { method: "POST",
    headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  if (r.ok) download(`${current.type}.${format}`, r.headers.get("Content-Type"), await r.blob());
}

async function exportReport() {
  // the design's report: one HTML page that stands alone, with the load and bound shown
  if (!current) return;
  const body = { mechanism: { type: current.type, params: current.params },
    crank_angle_deg: (frame * 360) / FRAMES };
  if (current.load) body.load = current.load; // in the design's unit
  else body.length_unit = current.unit;
  if (current.bound !== null && current.bound !== undefined) body.targets = { bound_deg: current.bound };
  const r = await fetch(new URL("v1/report", BASE), { method: "POST",
    headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  if (r.ok) download(`${current.type}-report.html`, r.headers.get("Content-Type"), await r.blob());
}

// ---- state in the address --------------------------------------------------------------------

function saveState(view, state) {
  const q = new URLSearchParams(state);
  history.replaceState(null, "", `#${view}?${q}`);
}

async function route(run) {
  const [view, query] = (location.hash.slice(1) || "synthesize").split("?");
  const name = ["synthesize", "analyze", "sweep"].includes(view) ? view : "synthesize";
  for (const v of ["synthesize", "analyze", "sweep"]) {
    $(`view-${v}`).hidden = v !== name;
    if (v === name) $(`tab-${v}`).setAttribute("aria-current", "page"); else $(`tab-${v}`).removeAttribute("aria-current");
  }
  const q = new URLSearchParams(query || "");
  if (name === "synthesize") {
    loadSynthState(q);
    if (run && query) await synthesize(Number(q.get("choose") || 0));
  } else {
    const prefix = name === "analyze" ? "a" : "s";
    const t = q.get("type") || $(`${prefix}-type`).value;
    $(`${prefix}-type`).value = t;
    const given = query ? Object.fromEntries(q) : null;
    await paramInputs(prefix, t, given);
    if (prefix === "a") setLoadState("a", q);
    if (given) {
      for (const k of ["start", "stop", "points", "unit", "rpm"]) {
        if (given[`__${k}`] !== undefined && $(`${prefix}-${k}`)) $(`${prefix}-${k}`).value = given[`__${k}`];
      }
    }
    if (run && query) await (name === "analyze" ? analyzeView() : sweepView());
  }
}

function buildObjectives(schema) {
  // the objectives a request may name, in the service's order, in the words its schema gives
  const o = schema.components.schemas.SynthesizeRequest.properties.objective;
  const titles = o["x-titles"] || {};
  Object.assign(OBJECTIVE_TITLES, titles);
  for (const k of o["x-searched"] || []) SEARCHED.add(k);
  $("objective").replaceChildren(...o.enum.map((k) => el("option", { value: k }, titles[k] || k)));
  $("objective").value = o.default;
}

async function init() {
  const [r, schema] = await Promise.all([api("v1/mechanisms"), api("openapi.json")]);
  for (const m of r.data) TYPES[m.type] = m;
  buildObjectives(schema.data);
  buildTypes();
  for (const slot of document.querySelectorAll(".load-slot")) slot.replaceWith(loadBox(slot.dataset.prefix));
  for (const prefix of ["a", "s"]) {
    const sel = $(`${prefix}-type`);
    sel.replaceChildren(...Object.values(TYPES).map((m) => el("option", { value: m.type }, m.title)));
    sel.value = "drag_link_slider" in TYPES ? "drag_link_slider" : Object.keys(TYPES)[0];
    sel.addEventListener("change", () => paramInputs(prefix, sel.value));
  }
  $("s-vary").addEventListener("change", setSweepRange);
  for (const u of document.querySelectorAll("select.unit")) u.addEventListener("change", showUnits);
  $("synth-form").addEventListener("submit", (e) => { e.preventDefault(); synthesize(0); });
  $("analyze-form").addEventListener("submit", (e) => { e.preventDefault(); analyzeView(); });
  $("sweep-form").addEventListener("submit", (e) => { e.preventDefault(); sweepView(); });
  $("play").addEventListener("click", () => play(timer === null));
  $("angle").addEventListener("input", () => { play(false); setFrame(Number($("angle").value)); });
  $("export-json").addEventListener("click", () => current && download(`${current.type}.json`,
    "application/json", JSON.stringify({ type: current.type, params: current.params, analysis: current.analysis }, null, 2)));
  $("export-svg").addEventListener("click", () => exportDrawing("svg"));
  $("export-dxf").addEventListener("click", () => exportDrawing("dxf"));
  $("export-gif").addEventListener("click", () => exportDrawing("gif"));
  $("export-report").addEventListener("click", exportReport);
  window.addEventListener("hashchange", () => route(false));
  await route(true);
  document.body.dataset.ready = "true";
}

init();
