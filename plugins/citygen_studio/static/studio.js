// citygen studio: the map of the scene's footprints, the selected building in 3D (its GLB), a ruleset editor
// and a live 2D preview of the facade while typing. Everything is computed by the server's JSON API.

const $ = (id) => document.getElementById(id);
const SVG = "http://www.w3.org/2000/svg";
// label colours of `citygen facade --png` (citygen/preview.py)
const LABEL_COLOURS = {wall: "#decdaa", window: "#466ea0", door: "#784628", balcony: "#5a5a64", sill: "#f0f0eb",
  cornice: "#fafaf5", pillar: "#beb4a0", shop: "#28466e", blind: "#3c7846", deco: "#e6dcc8", molding: "#f5f0e1",
  ledge: "#c8c3b9", roof: "#505055", frame: "#8a8f96", glass: "#6f93b8"};
const MODES = {split: "citygen-grammar", layers: "citygen-layers", relayout: "citygen-relayout", safe: "citygen-safe"};
const PREVIEW_DELAY = 250, BUILD_DELAY = 700;

const state = {info: null, buildings: [], selected: null, built: null, ruleset: null, texts: {}, saved: {},
  annotations: [], previews: 0, builds: 0, picks: 0, face: null};
window.studio = state;  // (for the end-to-end tests and the curious)

async function api(path, body) {
  const options = body === undefined ? {} :
    {method: "POST", headers: {"content-type": "application/json"}, body: JSON.stringify(body)};
  const response = await fetch(path, options);
  const data = await response.json();
  if (!response.ok) {
    const error = new Error(data.error ? data.error.message : response.statusText);
    error.data = data.error;
    throw error;
  }
  return data;
}

function status(text) { $("status").textContent = text; }

function where(error) {
  if (!error) return "";
  const place = error.file ? [error.file, error.line, error.column].filter((v) => v != null).join(":") + ": " : "";
  return place + error.message + (error.hint ? " -- " + error.hint : "");
}

function colourOf(text) {
  let h = 0;
  for (const c of text || "") h = (h * 31 + c.charCodeAt(0)) >>> 0;
  return text ? `hsl(${h % 360}, 45%, 62%)` : "#cccccc";
}

function element(name, attributes, parent) {
  const node = document.createElementNS(SVG, name);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  if (parent) parent.appendChild(node);
  return node;
}

// ---- map -------------------------------------------------------------------------------------------------------

function drawMap() {
  const map = $("map");
  map.replaceChildren();
  const points = state.buildings.flatMap((b) => b.rings.flat());
  if (!points.length) return;
  const xs = points.map((p) => p[0]), ys = points.map((p) => p[1]);
  const x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
  const pad = 0.03 * Math.max(x1 - x0, y1 - y0, 1);
  map.setAttribute("viewBox", `${x0 - pad} ${-y1 - pad} ${x1 - x0 + 2 * pad} ${y1 - y0 + 2 * pad}`);
  for (const building of state.buildings) {
    const d = building.rings.map((ring) => "M" + ring.map((p) => `${p[0]},${-p[1]}`).join("L") + "Z").join("");
    const ruleset = building.rulesets.street;
    const path = element("path", {d, fill: colourOf(ruleset), "data-index": building.index}, map);
    const title = element("title", {}, path);
    title.textContent = `${building.id}\nruleset: ${ruleset || "none"}\n` + Object.entries(building.attributes)
      .map(([k, v]) => `${k}: ${v}`).join("\n");
    path.addEventListener("click", () => select(building.index));
  }
}

// ---- 3D view ---------------------------------------------------------------------------------------------------

let view = null;  // the 3D view: view3d.js (three.js) is fetched on the first selection, not before the first paint

function viewReady() {
  view = view || import("./view3d.js").then(({createView}) => createView($("view3d"),
    () => (state.built && state.built.faces) || [],
    (face) => { state.picks++; $("face").value = String(face.index); showFace(); status(`face ${face.index} picked`); },
    (error) => status("cannot show the building: " + error)));
  return view;
}

async function showGlb(base64, frame) { (await viewReady()).show(base64, frame); }

// ---- facade drawing --------------------------------------------------------------------------------------------

function drawFacade(layout, svg = $("facade")) {
  svg.replaceChildren();
  if (!layout) return;
  const {width: w, height: h} = layout;
  svg.setAttribute("viewBox", `-0.2 -0.2 ${w + 0.4} ${h + 0.4}`);
  const layers = [];
  for (const r of layout.leaves) if (!layers.includes(r.layer)) layers.push(r.layer);
  for (const layer of layers) {  // back to front, as `citygen facade --png`
    for (const r of layout.leaves) {
      if (r.layer !== layer || r.label == null || r.w <= 0 || r.h <= 0) continue;
      const rect = element("rect", {x: r.x, y: h - r.y - r.h, width: r.w, height: r.h,
        fill: LABEL_COLOURS[r.label] || colourOf(r.label), "data-label": r.label}, svg);
      element("title", {}, rect).textContent = `${r.label} (${r.symbol})` + (r.material ? ` ${r.material}` : "") +
        ` ${r.w.toFixed(2)} x ${r.h.toFixed(2)} m`;
    }
  }
  for (const y of layout.floor_lines.slice(1, -1)) element("line", {class: "floor", x1: 0, x2: w, y1: h - y, y2: h - y}, svg);
  if (layers.length > 1) {  // a layer stack's alignment columns: region edges that several layers share
    const edges = new Map();
    for (const r of layout.leaves) {
      if (r.label == null) continue;
      for (const x of [r.x, r.x + r.w]) {
        const key = x.toFixed(2);
        if (x > 1e-6 && x < w - 1e-6) edges.set(key, (edges.get(key) || new Set()).add(r.layer));
      }
    }
    for (const [x, owners] of edges) {
      if (owners.size > 1) element("line", {class: "column", x1: x, x2: x, y1: 0, y2: h}, svg);
    }
  }
}

// ---- editor ----------------------------------------------------------------------------------------------------

let editor = null;

function modeFor(name) {
  const kind = state.info.kinds.find((k) => k.suffixes.some((s) => name.endsWith(s)));
  return kind ? MODES[kind.id] || null : null;
}

function completions(cm) {
  const cursor = cm.getCursor(), line = cm.getLine(cursor.line);
  let start = cursor.ch;
  while (start > 0 && /\w/.test(line[start - 1])) start--;
  const prefix = line.slice(start, cursor.ch);
  const symbols = cm.getValue().match(/\b[A-Z]\w*/g) || [];
  const words = [...new Set([...symbols, ...state.info.labels, ...state.info.materials])].sort();
  return {list: words.filter((w) => w.startsWith(prefix) && w !== prefix),
    from: CodeMirror.Pos(cursor.line, start), to: CodeMirror.Pos(cursor.line, cursor.ch)};
}

function setUpEditor() {
  editor = CodeMirror.fromTextArea($("editor"), {
    lineNumbers: true, gutters: ["CodeMirror-lint-markers", "CodeMirror-linenumbers"],
    lint: {getAnnotations: () => state.annotations, lintOnChange: false},
    extraKeys: {"Ctrl-Space": "autocomplete"}, hintOptions: {hint: completions, completeSingle: false},
  });
  editor.on("change", () => {
    if (!state.ruleset) return;
    state.texts[state.ruleset] = editor.getValue();
    $("save").disabled = state.texts[state.ruleset] === state.saved[state.ruleset];
    schedule("preview", preview, PREVIEW_DELAY);
    if (state.selected != null) schedule("build", build, BUILD_DELAY);
  });
}

async function openRuleset(name) {
  if (!name) return;
  if (!(name in state.texts)) {
    const data = await api("/api/ruleset?name=" + encodeURIComponent(name));
    state.texts[name] = state.saved[name] = data.text;
  }
  state.ruleset = name;
  $("ruleset").value = name;
  editor.setOption("mode", modeFor(name));
  editor.setValue(state.texts[name]);
  $("save").disabled = state.texts[name] === state.saved[name];
}

async function save() {
  const name = state.ruleset, text = state.texts[name];
  try {
    await api("/api/ruleset", {name, text});
    state.saved[name] = text;
    $("save").disabled = true;
    status(`saved ${name}`);
  } catch (error) { $("error").textContent = where(error.data) || error.message; }
}

// ---- live loop -------------------------------------------------------------------------------------------------

const timers = {};
function schedule(key, fn, delay) { clearTimeout(timers[key]); timers[key] = setTimeout(fn, delay); }

function size() {
  const number = (id) => Number($(id).value);
  return {width: number("width"), height: number("height"), floor_height: number("floor"), seed: number("seed")};
}

async function preview() {
  if (!state.ruleset) return;
  const started = performance.now();
  let result;
  const onFace = state.face ? {building: state.face.building, face: state.face.face} : {};
  try {
    result = await api("/api/preview", {ruleset: state.ruleset, text: editor.getValue(), ...size(), ...onFace});
  } catch (error) {
    $("error").textContent = where(error.data) || error.message;
    return;
  }
  state.previews++;
  const error = result.error;
  state.annotations = error && error.line ? [{severity: "error", message: where(error),
    from: CodeMirror.Pos(error.line - 1, Math.max(0, (error.column || 1) - 1)),
    to: CodeMirror.Pos(error.line - 1, (error.column || 1))}] : [];
  editor.performLint();
  $("error").textContent = error ? where(error) : result.problems.join("\n");
  if (result.request && state.face) showRequest(result.request);
  if (!error) {
    drawFacade(result.layout);
    $("explain").textContent = result.explain;
  }
  $("facade").dataset.ok = String(!error);
  status(`preview ${result.kind}: ${Math.round(performance.now() - started)} ms`);
}

// The distinct layouts of the edited ruleset over the next seeds (relayout and SAFE variations, a grammar's random
// choices); clicking one previews its seed.
async function variations() {
  const grid = $("variations");
  grid.replaceChildren();
  grid.hidden = false;
  let result;
  try {
    result = await api("/api/variations", {ruleset: state.ruleset, text: editor.getValue(), ...size(), count: 8});
  } catch (error) { $("error").textContent = where(error.data) || error.message; return; }
  if (result.error) { $("error").textContent = where(result.error); return; }
  for (const variation of result.variations) {
    const cell = document.createElement("figure");
    cell.className = "variation";
    cell.dataset.seed = variation.seed;
    const caption = document.createElement("figcaption");
    caption.textContent = `seed ${variation.seed}` + (variation.error ? ": " + variation.error.message : "");
    if (variation.layout) drawFacade(variation.layout, element("svg", {}, cell));
    cell.appendChild(caption);
    cell.addEventListener("click", () => {
      $("seed").value = variation.seed;
      freeSize();
      for (const other of grid.children) other.classList.toggle("picked", other === cell);
      preview();
    });
    grid.appendChild(cell);
  }
  status(`${result.variations.length} distinct variations`);
}

// ---- inverse tools -------------------------------------------------------------------------------------------

function base64Of(file) {
  return new Promise((resolve, reject) => {
    const reader = new FileReader();
    reader.onload = () => resolve(String(reader.result).split(",", 2)[1] || "");
    reader.onerror = () => reject(reader.error);
    reader.readAsDataURL(file);
  });
}

// The import options as the command line takes them: a CMP annotation's tolerances, a photo's crop and parser.
function importOptions() {
  const crop = $("crop").value.trim() ? $("crop").value.trim().split(/[\s,]+/).map(Number) : null;
  if (crop && (crop.length !== 4 || crop.some((v) => !Number.isFinite(v)))) {
    throw new Error("crop: give four pixel numbers x0 y0 x1 y1 (y down)");
  }
  return {snap: Number($("snap").value), align: Number($("align").value), equal_sizes: Number($("equal-sizes").value),
    element_caps: $("element-caps").checked, drop_degenerate: $("drop-degenerate").checked, parser: $("parser").value,
    crop};
}

// The dropped photo, on which a drag sets the crop box (in the photo's pixels).
function showPhoto(file) {
  const holder = $("photo-crop"), photo = $("photo");
  holder.hidden = !file;
  if (!file) return;
  if (photo.src) URL.revokeObjectURL(photo.src);
  photo.src = URL.createObjectURL(file);
  $("crop-box").hidden = true;
}

function setUpCrop() {
  const holder = $("photo-crop"), photo = $("photo"), box = $("crop-box");
  let start = null;
  const at = (e) => {
    const r = photo.getBoundingClientRect();
    return [Math.min(Math.max(e.clientX - r.left, 0), r.width), Math.min(Math.max(e.clientY - r.top, 0), r.height)];
  };
  const draw = (a, b) => {
    Object.assign(box.style, {left: `${Math.min(a[0], b[0])}px`, top: `${Math.min(a[1], b[1])}px`,
      width: `${Math.abs(b[0] - a[0])}px`, height: `${Math.abs(b[1] - a[1])}px`});
    box.hidden = false;
  };
  holder.addEventListener("pointerdown", (e) => { start = at(e); holder.setPointerCapture(e.pointerId); });
  holder.addEventListener("pointermove", (e) => { if (start) draw(start, at(e)); });
  holder.addEventListener("pointerup", (e) => {
    if (!start) return;
    const end = at(e), scale = photo.naturalWidth / photo.getBoundingClientRect().width;
    const [x0, x1] = [start[0], end[0]].sort((a, b) => a - b), [y0, y1] = [start[1], end[1]].sort((a, b) => a - b);
    start = null;
    if (x1 - x0 < 4 || y1 - y0 < 4) return;  // (a click, not a box)
    $("crop").value = [x0, y0, x1, y1].map((v) => Math.round(v * scale)).join(" ");
    if (state.dropped) importFiles(state.dropped);
  });
}

// A dropped photo, layout JSON or CMP annotation (its XML, with the label-map PNG of the same name when dropped
// together) becomes a layout, drawn in the facade view, ready for grammar extraction.
async function importFiles(files) {
  const list = [...files];
  state.dropped = list;
  $("reimport").disabled = !list.length;
  const xml = list.find((f) => f.name.toLowerCase().endsWith(".xml"));
  const file = xml || list[0];
  if (!file) return;
  const stem = file.name.replace(/\.[^.]*$/, "");
  const labelMap = xml && list.find((f) => f.name.toLowerCase() === (stem + ".png").toLowerCase());
  const photo = !xml && !file.name.toLowerCase().endsWith(".json");
  if (photo && state.photo !== file) { state.photo = file; $("crop").value = ""; showPhoto(file); }
  if (!photo) { state.photo = null; showPhoto(null); }
  $("import-summary").textContent = `reading ${file.name} ...`;
  try {
    const width = Number($("photo-width").value) || null;
    const result = await api("/api/import", {name: file.name, data: await base64Of(file), width,
      floor_height: Number($("floor").value), label_map: labelMap ? await base64Of(labelMap) : null,
      options: importOptions()});
    state.imported = {name: file.name, layout: result.layout};
    drawFacade(result.drawing);
    $("import-summary").textContent = result.summary;
    $("extract").disabled = false;
  } catch (error) { $("import-summary").textContent = where(error.data) || error.message; }
}

// The imported layout's grammar (wu2014; the size-independent one, for any face) opened in the editor, unsaved.
async function extractGrammar() {
  if (!state.imported) return;
  $("extract").disabled = true;
  $("import-summary").textContent = "extracting ...";
  try {
    const result = await api("/api/extract", {layout: state.imported.layout, method: $("method").value,
      iterations: Number($("iterations").value)});
    const name = state.imported.name.replace(/\.[^.]*$/, "") + ".extracted.grammar";
    state.texts[name] = result.size_independent || result.text;
    state.saved[name] = null;
    if (![...$("ruleset").options].some((o) => o.value === name)) $("ruleset").add(new Option(name, name));
    await openRuleset(name);
    $("import-summary").textContent = `${name}: cost ${result.cost.toFixed(2)}, ${result.rules} rules, ` +
      `${result.seconds.toFixed(2)} s (not saved yet)`;
  } catch (error) {
    $("import-summary").textContent = where(error.data) || error.message;
  } finally { $("extract").disabled = false; }
}

function setUpInverse() {
  const panel = $("inverse-panel");
  $("drop").addEventListener("change", () => importFiles($("drop").files));
  $("extract").addEventListener("click", extractGrammar);
  $("reimport").addEventListener("click", () => state.dropped && importFiles(state.dropped));
  setUpCrop();
  panel.addEventListener("dragover", (e) => { e.preventDefault(); panel.classList.add("dragging"); });
  panel.addEventListener("dragleave", () => panel.classList.remove("dragging"));
  panel.addEventListener("drop", (e) => {
    e.preventDefault();
    panel.classList.remove("dragging");
    panel.open = true;
    importFiles(e.dataTransfer.files);
  });
}

// ---- generate ------------------------------------------------------------------------------------------------------

// Run the whole scene on the server with the rulesets as the editor has them (unsaved edits read in place of their
// files, which are not written), follow its progress, then show the report and the file.
async function generate() {
  $("generate").disabled = true;
  $("download").hidden = true;
  $("progress").hidden = false;
  try {
    await api("/api/generate", {format: $("format").value, jobs: 1, rulesets: edited()});
    const run = await new Promise((resolve, reject) => {  // progress pushed by the server until the run ends
      const events = new EventSource("/api/generate/events");
      events.onmessage = (event) => {
        const state = JSON.parse(event.data);
        $("progress").max = Math.max(state.total, 1);
        $("progress").value = state.done;
        status(`generating: ${state.done} / ${state.total} buildings`);
        if (!state.running) { events.close(); resolve(state); }
      };
      events.onerror = () => { events.close(); reject(new Error("lost the progress of the run")); };
    });
    $("progress").value = $("progress").max;
    if (run.error) throw Object.assign(new Error(run.error.message), {data: run.error});
    $("report").textContent = (run.edited.length ? `from the unsaved edits of ${run.edited.join(", ")} ` +
      "(their files not written)\n" : "") + run.report.summary;
    $("download").href = "/api/output?name=" + encodeURIComponent(run.output);
    $("download").textContent = "download " + run.output;
    $("download").hidden = false;
    status(`generated ${run.report.written} buildings`);
  } catch (error) {
    $("report").textContent = where(error.data) || error.message;
  } finally {
    $("generate").disabled = false;
  }
}

function edited() {
  return Object.fromEntries(Object.entries(state.texts).filter(([name, text]) => text !== state.saved[name]));
}

async function build(frame = false) {
  const index = state.selected;
  status("building " + state.buildings[index].id + " ...");
  let result;
  try {
    result = await api("/api/build", {index, rulesets: edited()});
  } catch (error) {
    $("error").textContent = where(error.data) || error.message;
    status("build failed");
    return;
  }
  if (index !== state.selected) return;
  state.built = result;
  state.builds++;
  if (result.skipped) { status(`${result.id} skipped: ${result.skipped}`); return; }
  showGlb(result.glb, frame);
  const faces = result.faces.filter((f) => f.layout);
  const choice = $("face"), previous = choice.value;
  choice.replaceChildren(...faces.map((f) => {
    const option = document.createElement("option");
    option.value = f.index;
    option.textContent = `face ${f.index}${f.courtyard ? " (courtyard)" : ""}: ${f.width.toFixed(1)} x ${f.height.toFixed(1)} m`;
    return option;
  }));
  if (faces.some((f) => String(f.index) === previous)) choice.value = previous;
  status(`${result.id}: ${faces.length} dressed faces` + (result.warnings.length ? `, ${result.warnings.length} warnings` : ""));
  showFace(frame);
}

// The selected face as the building got it (its floors, entrance and corners from the building's coordinator); the
// previews while typing then dress this face under the same request, until a size or seed is set by hand.
function showFace(resize = true) {
  const face = state.built && state.built.faces.find((f) => String(f.index) === $("face").value);
  if (!face) return;
  if (resize) {
    $("width").value = face.width.toFixed(2);
    $("height").value = face.height.toFixed(2);
  }
  const picked = !state.face || state.face.building !== state.selected || state.face.face !== face.index;
  state.face = {building: state.selected, face: face.index, id: state.built.id};
  drawFacade(face.layout);
  showRequest(face.request);
  if (picked) {  // (a rebuild keeps the account of the last preview of this face)
    $("explain").textContent = `face ${face.index} of ${state.built.id} as built`;
    schedule("preview", preview, 0);  // its account and what the city does with it
  }
}

// What the building's coordinator asks of the previewed face.
function showRequest(request) {
  const corners = request.corner_widths.some((w) => w > 0) ?
    `, corner strips ${request.corner_widths.map((w) => w.toFixed(2)).join(" / ")} m` : "";
  $("face-mode").textContent = `face ${state.face.face} of ${state.face.id} as the city gets it: ` +
    `${request.width.toFixed(2)} x ${request.height.toFixed(2)} m, floor lines ` +
    `${request.floor_lines.map((y) => y.toFixed(2)).join(", ")}` + (request.entrance ? ", the entrance" : "") + corners;
}

// Previews at the size and seed of the controls, not on the building's face.
function freeSize() {
  state.face = null;
  $("face-mode").textContent = "free size: the controls' width, height, floor height and seed";
}

async function select(index) {
  state.selected = index;
  freeSize();  // (until the building's faces are known)
  const building = state.buildings[index];
  for (const path of $("map").querySelectorAll("path")) path.classList.toggle("selected", path.dataset.index === String(index));
  $("building-title").textContent = building.id;
  $("building-info").textContent = `${building.id}\nstreet: ${building.rulesets.street || "none"}\ncourtyard: ` +
    `${building.rulesets.courtyard || "none"}\n` + Object.entries(building.attributes).map(([k, v]) => `${k}: ${v}`).join("\n");
  if (building.rulesets.street && building.rulesets.street !== state.ruleset) await openRuleset(building.rulesets.street);
  await build(true);
}

async function start() {
  state.info = await api("/api/scene");
  setUpEditor();
  $("scene-name").textContent = state.info.scene ? `${state.info.scene} (${state.info.file})` : "no scene";
  if (state.info.error) {
    $("banner").hidden = false;
    $("banner").textContent = "The scene did not load: " + where(state.info.error);
  }
  $("floor").value = state.info.floor_height;
  $("ruleset").replaceChildren(...state.info.rulesets.map((name) => new Option(name, name)));
  $("ruleset").addEventListener("change", () => openRuleset($("ruleset").value));
  $("save").addEventListener("click", save);
  $("face").addEventListener("change", () => showFace());
  $("vary").addEventListener("click", variations);
  $("generate").addEventListener("click", generate);
  setUpInverse();
  $("generate").disabled = !state.info.scene;
  for (const id of ["width", "height", "floor", "seed"]) {
    $(id).addEventListener("input", () => { freeSize(); schedule("preview", preview, PREVIEW_DELAY); });
  }
  if (state.info.rulesets.length) await openRuleset(state.info.rulesets[0]);
  if (state.info.scene) {  // (the editor works while the server builds the footprints and masses)
    status("loading the buildings ...");
    state.buildings = (await api("/api/buildings")).buildings;
    drawMap();
  }
  status("ready");
  document.body.dataset.ready = "true";
  if (state.info.scene) viewReady();  // (three.js fetched now, so the first selection shows at once)
}

start().catch((error) => { $("banner").hidden = false; $("banner").textContent = error.message; });
