// The job viewer: a job list, and per job its case, the material points of
// a chosen step coloured by a field with the B-spline boundary over them,
// and plots of the probes, reactions and Newton iterations. Plain modules,
// no build step: `mpm serve` embeds this file as it is.

const app = document.getElementById('app');
// The token form, kept here: pages replace what `app` holds.
const tokenForm = document.getElementById('token-form');
const tokenInput = document.getElementById('token-input');
const tokenError = document.getElementById('token-error');
const TOKEN_KEY = 'mpm-token';
const REFRESH_MS = 2000;

// ---- the API, with the bearer token kept for the tab ----

class Unauthorized extends Error {}

function authorization() {
  const token = sessionStorage.getItem(TOKEN_KEY);
  return token ? { Authorization: `Bearer ${token}` } : {};
}

async function api(path) {
  const response = await fetch(path, { headers: authorization() });
  if (response.status === 401) throw new Unauthorized();
  const body = await response.json().catch(() => null);
  if (!response.ok) {
    const e = body && body.error;
    throw new Error(e ? `${e.code}: ${e.message}` : `${path}: HTTP ${response.status}`);
  }
  return body;
}

// Asks for the token, then shows the page again.
function askForToken() {
  app.replaceChildren(tokenForm);
  tokenForm.hidden = false;
  tokenError.hidden = !sessionStorage.getItem(TOKEN_KEY);
  tokenError.textContent = 'That token was refused.';
  tokenForm.onsubmit = (event) => {
    event.preventDefault();
    sessionStorage.setItem(TOKEN_KEY, tokenInput.value);
    tokenForm.hidden = true;
    document.body.append(tokenForm);
    route();
  };
}

// ---- small DOM helpers ----

function el(tag, attributes = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attributes)) {
    if (key === 'class') node.className = value;
    else if (key.startsWith('on')) node.addEventListener(key.slice(2), value);
    else node.setAttribute(key, value);
  }
  node.append(...children.filter((c) => c !== null && c !== undefined));
  return node;
}

const SVG = 'http://www.w3.org/2000/svg';
function svg(tag, attributes = {}) {
  const node = document.createElementNS(SVG, tag);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  return node;
}

function statusBadge(status) {
  return el('span', { class: `status status-${status}` }, status);
}

function formatNumber(v) {
  if (!Number.isFinite(v)) return String(v);
  const a = Math.abs(v);
  if (a !== 0 && (a < 1e-3 || a >= 1e5)) return v.toExponential(3);
  return Number(v.toPrecision(4)).toString();
}

// ---- routing: #/ is the list, #/jobs/ID a job ----

let leavePage = () => {};
// Counts navigations: a page still loading when the user moves on finds
// itself stale and leaves `app` alone.
let navigation = 0;

function route() {
  leavePage();
  leavePage = () => {};
  const mine = ++navigation;
  const stale = () => mine !== navigation;
  const match = location.hash.match(/^#\/jobs\/(\d+)/);
  const show = match ? () => jobPage(Number(match[1]), stale) : () => jobList(stale);
  show().catch((e) => stale() || failed(e));
}

function failed(e) {
  if (e instanceof Unauthorized) askForToken();
  else app.replaceChildren(el('p', { class: 'error' }, String(e.message || e)));
}

// A page that refreshes itself until it is left.
function everyFewSeconds(refresh, stale) {
  if (stale()) return;
  let timer = null;
  let left = false;
  const tick = async () => {
    try {
      await refresh();
    } catch (e) {
      if (e instanceof Unauthorized) return failed(e);
    }
    if (!left) timer = setTimeout(tick, REFRESH_MS);
  };
  timer = setTimeout(tick, REFRESH_MS);
  leavePage = () => {
    left = true;
    clearTimeout(timer);
  };
}

// ---- the job list ----

async function jobList(stale) {
  const table = el('table', { class: 'jobs' });
  const fill = (page) => {
    const rows = page.jobs.map((job) =>
      el('tr', { 'data-job': job.id },
        el('td', {}, el('a', { href: `#/jobs/${job.id}` }, `#${job.id}`)),
        el('td', {}, job.title || ''),
        el('td', {}, statusBadge(job.status)),
        el('td', {},
          el('progress', { max: job.progress.of, value: job.progress.step }),
          ` ${job.progress.step}/${job.progress.of}`),
        el('td', { class: 'num' }, job.points),
        el('td', { class: 'num' }, job.newton_iterations),
        el('td', { class: 'num' }, job.solve_seconds == null ? '' : job.solve_seconds.toFixed(2)),
      ));
    table.replaceChildren(
      el('tr', {}, ...['job', 'title', 'status', 'load steps', 'points', 'Newton iterations', 'solve (s)']
        .map((h) => el('th', {}, h))),
      ...rows);
  };
  const page = await api('/jobs?limit=100');
  if (stale()) return;
  fill(page);
  const total = el('p', { class: 'note' });
  const note = (p) => { total.textContent = `${p.total} jobs, newest first; this list updates every ${REFRESH_MS / 1000} s.`; };
  note(page);
  app.replaceChildren(el('h1', {}, 'Jobs'), total, table);
  document.title = 'mpm jobs';
  everyFewSeconds(async () => {
    const p = await api('/jobs?limit=100');
    fill(p);
    note(p);
  }, stale);
}

// ---- one job ----

// The fields a point can be coloured by: label, unit, value of point i.
const FIELDS = [
  { key: 'u', label: 'displacement |u|', unit: 'm', needs: 'displacement',
    value: (c, i) => Math.hypot(c.displacement[i][0], c.displacement[i][1]) },
  { key: 'ux', label: 'displacement u_x', unit: 'm', needs: 'displacement', value: (c, i) => c.displacement[i][0] },
  { key: 'uy', label: 'displacement u_y', unit: 'm', needs: 'displacement', value: (c, i) => c.displacement[i][1] },
  { key: 'sxx', label: 'stress σ_xx', unit: 'Pa', needs: 'stress', value: (c, i) => c.stress[i][0] },
  { key: 'syy', label: 'stress σ_yy', unit: 'Pa', needs: 'stress', value: (c, i) => c.stress[i][1] },
  { key: 'sxy', label: 'stress σ_xy', unit: 'Pa', needs: 'stress', value: (c, i) => c.stress[i][2] },
  { key: 'szz', label: 'stress σ_zz', unit: 'Pa', needs: 'stress', value: (c, i) => c.stress[i][3] },
  { key: 'J', label: 'volume ratio J', unit: '–', needs: 'jacobian', value: (c, i) => c.jacobian[i] },
  { key: 'ep', label: 'plastic strain', unit: '–', needs: 'plastic_strain', value: (c, i) => c.plastic_strain[i] },
  { key: 'body', label: 'body', unit: 'index', needs: 'body', value: (c, i) => c.body[i] },
];

// A 3D job's fields: vectors of three components, the stress tensor's six
// ([xx, yy, zz, xy, yz, xz]).
const SOLID_FIELDS = [
  { key: 'u', label: 'displacement |u|', unit: 'm', needs: 'displacement', value: (c, i) => Math.hypot(...c.displacement[i]) },
  ...['x', 'y', 'z'].map((axis, k) => (
    { key: `u${axis}`, label: `displacement u_${axis}`, unit: 'm', needs: 'displacement', value: (c, i) => c.displacement[i][k] })),
  ...['xx', 'yy', 'zz', 'xy', 'yz', 'xz'].map((pair, k) => (
    { key: `s${pair}`, label: `stress σ_${pair}`, unit: 'Pa', needs: 'stress', value: (c, i) => c.stress[i][k] })),
  ...FIELDS.filter((f) => ['J', 'ep', 'body'].includes(f.key)),
];

// Whether a step's points are a 3D job's (positions of three components).
const isSolid = (columns) => columns.position.length > 0 && columns.position[0].length === 3;
const fieldsOf = (columns) => (isSolid(columns) ? SOLID_FIELDS : FIELDS);

// Step documents kept per page: they may hold a million points each.
const CACHED_STEPS = 6;

async function jobPage(id, stale) {
  const [job, kase] = await Promise.all([api(`/jobs/${id}`), api(`/jobs/${id}/case`)]);
  if (stale()) return;
  document.title = `mpm job ${id}`;
  const steps = new Map(); // step number -> step document, oldest first
  const loadStep = async (k) => {
    if (!steps.has(k)) {
      steps.set(k, await api(`/jobs/${id}/steps/${k}`));
      if (steps.size > CACHED_STEPS) steps.delete(steps.keys().next().value);
    }
    return steps.get(k);
  };
  // Which steps keep their points (the case's `output.every`, and the last).
  const every = (kase.output && kase.output.every) || 1;
  const stored = (k) => k === 0 || k === job.progress.of || k % every === 0;
  const latestStored = (k) => {
    while (k > 0 && !stored(k)) k--;
    return k;
  };

  const heading = el('h1', {}, `Job #${id} `, statusBadge(job.status));
  const summary = el('p', { class: 'summary' });
  const errorBox = el('div', { class: 'error job-error', hidden: '' });
  // What the case and its steps warn of (the result's `warnings`).
  const warningBox = el('div', { class: 'warning job-warnings', hidden: '' });
  const slider = el('input', { type: 'range', min: 0, max: 0, value: 0, step: 1, id: 'step-slider' });
  const stepLabel = el('span', { id: 'step-label' });
  const fieldSelect = el('select', { id: 'field' });
  const canvas = el('canvas', { class: 'body', width: 820, height: 460, id: 'points' });
  const colourBar = el('canvas', { class: 'colourbar', width: 24, height: 300 });
  const barLabels = el('div', { class: 'legend' });
  const message = el('p', { class: 'note', id: 'step-note' });
  const plots = el('div', { class: 'plots' });
  const caseText = el('pre', {}, JSON.stringify(kase, null, 2));
  // The whole job as `mpm run` writes it; fetched with the token, saved
  // from memory.
  const download = el('button', { id: 'download' }, 'download all (zip)');
  download.addEventListener('click', async () => {
    const response = await fetch(`/jobs/${id}/archive`, { headers: authorization() });
    if (!response.ok) {
      message.textContent = `archive: HTTP ${response.status}`;
      return;
    }
    const url = URL.createObjectURL(await response.blob());
    el('a', { href: url, download: `job-${id}.zip` }).click();
    setTimeout(() => URL.revokeObjectURL(url), 10000);
  });
  app.replaceChildren(
    el('p', {}, el('a', { href: '#/' }, '← all jobs')),
    heading, summary, el('p', {}, download), errorBox, warningBox,
    el('div', { class: 'controls' },
      el('label', {}, 'load step ', slider), stepLabel,
      el('label', {}, 'colour by ', fieldSelect)),
    message,
    el('div', { class: 'view' }, canvas,
      el('div', { class: 'legend' }, colourBar, barLabels)),
    plots,
    el('details', {}, el('summary', {}, 'the case'), caseText),
  );

  let current = { job, result: null };
  let reference = null; // step 0's points, to keep the view's frame
  // A 3D job's view: turned by dragging, back to the start by a double click.
  const view = { ...START_VIEW };
  let lastDoc = null;
  let pending = false;
  const redrawView = () => {
    if (pending || !lastDoc || !isSolid(lastDoc.points)) return;
    pending = true;
    requestAnimationFrame(() => {
      pending = false;
      const field = SOLID_FIELDS.find((f) => f.key === fieldSelect.value) || null;
      drawSolid(canvas, lastDoc, reference, field, kase.grid, view);
    });
  };
  let dragged = null;
  canvas.addEventListener('pointerdown', (e) => { dragged = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener('pointerup', () => { dragged = null; });
  canvas.addEventListener('pointermove', (e) => {
    if (!dragged) return;
    view.yaw += 0.01 * (e.clientX - dragged[0]);
    view.pitch = Math.max(-Math.PI / 2, Math.min(Math.PI / 2, view.pitch + 0.01 * (e.clientY - dragged[1])));
    dragged = [e.clientX, e.clientY];
    redrawView();
  });
  canvas.addEventListener('dblclick', () => { Object.assign(view, START_VIEW); redrawView(); });
  const showJob = (j) => {
    heading.replaceChildren(`Job #${id} `, statusBadge(j.status));
    const seconds = j.solve_seconds == null ? '' : `, solved in ${j.solve_seconds.toFixed(2)} s`;
    summary.textContent = `${j.title || 'untitled'}: ${j.points} material points, ` +
      `${j.progress.step} of ${j.progress.of} load steps, ${j.newton_iterations} Newton iterations${seconds}. ` +
      `Grid cell size h = ${kase.grid.cell_size} m.`;
    if (j.error) {
      errorBox.hidden = false;
      const where = ['step', 'iteration', 'residual']
        .filter((k) => j.error[k] != null)
        .map((k) => `${k} ${formatNumber(j.error[k])}`).join(', ');
      errorBox.textContent = `${j.status}: ${j.error.kind}: ${j.error.message}${where ? ` (${where})` : ''}`;
    }
    // Follow the newest step with points while the slider is at the end.
    const atEnd = Number(slider.value) >= latestStored(Number(slider.max));
    slider.max = j.progress.step;
    if (atEnd) slider.value = latestStored(j.progress.step);
  };

  const draw = async () => {
    const k = Number(slider.value);
    stepLabel.textContent = `step ${k} of ${current.job.progress.of}`;
    let doc;
    try {
      doc = await loadStep(k);
      if (!reference) reference = (await loadStep(0)).points;
    } catch (e) {
      if (e instanceof Unauthorized) throw e;
      message.textContent = `step ${k}: ${e.message}`;
      return;
    }
    // The slider moved on while this step loaded.
    if (Number(slider.value) !== k) return;
    const lf = doc.report.load_factor;
    const stage = doc.report.stage ? `stage "${doc.report.stage}", ` : '';
    // A strength-reduction step: the factor its strengths are divided by.
    const sr = doc.report.strength_reduction;
    const strength = sr
      ? `, strength factor ${formatNumber(sr.factor)}${sr.found ? ' (the factor of safety)' : ''}`
      : '';
    stepLabel.textContent = `step ${k} of ${current.job.progress.of}, ${stage}load factor ${formatNumber(lf)}${strength}`;
    if (!doc.points) {
      message.textContent = `Step ${k}'s points were not stored (the case's output.every thins them).`;
      clear(canvas);
      return;
    }
    offerFields(fieldSelect, doc.points);
    // None when the case stores no column to colour by: one colour.
    const field = fieldsOf(doc.points).find((f) => f.key === fieldSelect.value) || null;
    lastDoc = doc;
    if (isSolid(doc.points)) {
      const drawn = drawSolid(canvas, doc, reference, field, kase.grid, view);
      drawColourBar(colourBar, barLabels, field, drawn.range, drawn.uniform);
      message.textContent = `${drawn.points} points drawn in 3D (x red, y green, z blue): ` +
        'drag to turn the view, double-click for the first one.';
      return;
    }
    const drawn = drawBody(canvas, doc, reference, field, kase.grid);
    drawColourBar(colourBar, barLabels, field, drawn.range, drawn.uniform);
    message.textContent = `${drawn.points} points and ${drawn.curves} boundary curve(s) drawn; ` +
      `grid lines every h = ${kase.grid.cell_size} m.`;
  };

  const showPlots = (result) => {
    plots.replaceChildren(...resultPlots(result, kase));
    const warnings = result.warnings || [];
    warningBox.hidden = warnings.length === 0;
    warningBox.replaceChildren(...warnings.map((w) => el('p', {}, `${w.kind}: ${w.message}`)));
  };

  showJob(job);
  slider.value = latestStored(job.progress.step);
  const redraw = () => draw().catch((e) => stale() || failed(e));
  slider.addEventListener('input', redraw);
  fieldSelect.addEventListener('change', redraw);
  if (job.progress.step > 0 || job.status !== 'queued') {
    current.result = await api(`/jobs/${id}/result`);
    if (stale()) return;
    showPlots(current.result);
  }
  await draw();

  if (job.status === 'queued' || job.status === 'running') {
    everyFewSeconds(async () => {
      const j = await api(`/jobs/${id}`);
      const grew = j.progress.step !== current.job.progress.step || j.status !== current.job.status;
      current.job = j;
      showJob(j);
      if (grew) {
        current.result = await api(`/jobs/${id}/result`);
        showPlots(current.result);
        await draw();
      }
      if (j.status !== 'queued' && j.status !== 'running') leavePage();
    }, stale);
  }
}

function offerFields(select, columns) {
  const available = fieldsOf(columns).filter((f) => columns[f.needs] && columns[f.needs].length);
  const keys = available.map((f) => f.key).join();
  if (select.dataset.keys === keys) return;
  const chosen = select.value;
  select.replaceChildren(...available.map((f) => el('option', { value: f.key }, `${f.label} (${f.unit})`)));
  if (available.some((f) => f.key === chosen)) select.value = chosen;
  select.dataset.keys = keys;
}

function clear(canvas) {
  canvas.getContext('2d').clearRect(0, 0, canvas.width, canvas.height);
  canvas.dataset.points = 0;
  canvas.dataset.curves = 0;
}

// A perceptually ordered colour map (viridis, sampled at nine stops).
const VIRIDIS = ['#440154', '#472d7b', '#3b528b', '#2c728e', '#21918c', '#28ae80', '#5ec962', '#addc30', '#fde725']
  .map((h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16)));

function colour(t) {
  const x = Math.min(1, Math.max(0, Number.isFinite(t) ? t : 0)) * (VIRIDIS.length - 1);
  const i = Math.min(VIRIDIS.length - 2, Math.floor(x));
  const f = x - i;
  const [a, b] = [VIRIDIS[i], VIRIDIS[i + 1]];
  return `rgb(${a.map((v, j) => Math.round(v + f * (b[j] - v))).join(',')})`;
}

// Draws the points of `doc` coloured by `field` and its boundary curves, in
// a frame that holds both this step and step 0, with equal axis scales.
function drawBody(canvas, doc, reference, field, grid) {
  const ctx = canvas.getContext('2d');
  const { width, height } = canvas;
  const c = doc.points;
  const n = c.position.length;
  let [x0, y0, x1, y1] = [Infinity, Infinity, -Infinity, -Infinity];
  const grow = ([x, y]) => { x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x); y1 = Math.max(y1, y); };
  c.position.forEach(grow);
  reference.position.forEach(grow);
  for (const b of doc.boundaries) b.polyline.forEach(grow);
  const pad = 0.06 * Math.max(x1 - x0, y1 - y0, 1e-12);
  [x0, y0, x1, y1] = [x0 - pad, y0 - pad, x1 + pad, y1 + pad];
  const scale = Math.min(width / (x1 - x0), height / (y1 - y0));
  const ox = (width - scale * (x1 - x0)) / 2;
  const oy = (height - scale * (y1 - y0)) / 2;
  const px = (x) => ox + (x - x0) * scale;
  const py = (y) => height - oy - (y - y0) * scale;

  ctx.clearRect(0, 0, width, height);
  // The background grid's lines, where the frame shows them.
  const h = grid.cell_size;
  const [gx, gy] = grid.origin || [0, 0];
  if (h * scale >= 4) {
    ctx.strokeStyle = '#e4e4e4';
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let x = gx + Math.ceil((x0 - gx) / h) * h; x <= x1; x += h) { ctx.moveTo(px(x), 0); ctx.lineTo(px(x), height); }
    for (let y = gy + Math.ceil((y0 - gy) / h) * h; y <= y1; y += h) { ctx.moveTo(0, py(y)); ctx.lineTo(width, py(y)); }
    ctx.stroke();
  }

  // One value everywhere (step 0's displacements): the bar says so rather
  // than show a made-up range around it.
  const { values, lo, hi, uniform } = fieldValues(c, field);
  // A point is drawn as a square of its own area (and half a pixel more, so
  // that neighbours meet), at least 2 px across.
  const side = (i) => Math.max(2, 0.5 + scale * Math.sqrt(c.volume && c.volume.length ? c.volume[i] : (h * h) / 4));
  for (let i = 0; i < n; i++) {
    const s = side(i);
    ctx.fillStyle = colour((values[i] - lo) / (hi - lo));
    ctx.fillRect(px(c.position[i][0]) - s / 2, py(c.position[i][1]) - s / 2, s, s);
  }
  // The B-spline boundary of each body (holes dashed).
  ctx.strokeStyle = '#d00';
  ctx.lineWidth = 2;
  for (const b of doc.boundaries) {
    ctx.setLineDash(b.hole ? [6, 4] : []);
    ctx.beginPath();
    b.polyline.forEach(([x, y], j) => (j ? ctx.lineTo(px(x), py(y)) : ctx.moveTo(px(x), py(y))));
    ctx.stroke();
  }
  ctx.setLineDash([]);
  // A scale bar of one cell.
  ctx.fillStyle = '#222';
  ctx.fillRect(12, height - 14, h * scale, 3);
  ctx.font = '12px sans-serif';
  ctx.fillText(`h = ${h} m`, 14 + h * scale + 6, height - 9);

  canvas.dataset.points = n;
  canvas.dataset.curves = doc.boundaries.length;
  return { points: n, curves: doc.boundaries.length, range: [lo, hi], uniform };
}

// A field's values at the points, their range, and the one value of a
// uniform field (whose range is then made up around it, and the bar says so).
function fieldValues(columns, field) {
  const n = columns.position.length;
  const values = Array.from({ length: n }, (_, i) => (field ? field.value(columns, i) : 0));
  let [lo, hi] = [Infinity, -Infinity];
  for (const v of values) if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  const uniform = !(hi > lo) ? (Number.isFinite(lo) ? lo : 0) : null;
  if (uniform !== null) [lo, hi] = [uniform - 0.5 * Math.abs(uniform || 1), uniform + 0.5 * Math.abs(uniform || 1)];
  return { values, lo, hi, uniform };
}

// The first view of a 3D job: turned 35 degrees about z and tilted 25
// degrees down, so that all three axes show.
const START_VIEW = { yaw: -0.6, pitch: 0.45 };

// Draws a 3D job's points as squares of their own size (the cube root of
// their volume) in an orthographic view turned by `view.yaw` about z and
// tilted by `view.pitch`, z up, the farthest drawn first; the frame holds
// this step and step 0 whichever way the view turns; an axis triad and a
// cell-size bar in the corner.
function drawSolid(canvas, doc, reference, field, grid, view) {
  const ctx = canvas.getContext('2d');
  const { width, height } = canvas;
  const c = doc.points;
  const n = c.position.length;
  const lo3 = [Infinity, Infinity, Infinity];
  const hi3 = [-Infinity, -Infinity, -Infinity];
  for (const x of [...c.position, ...reference.position]) {
    for (let k = 0; k < 3; k++) { lo3[k] = Math.min(lo3[k], x[k]); hi3[k] = Math.max(hi3[k], x[k]); }
  }
  const centre = lo3.map((l, k) => (l + hi3[k]) / 2);
  const radius = Math.max(0.5 * Math.hypot(...hi3.map((h, k) => h - lo3[k])), 1e-12);
  const scale = 0.45 * Math.min(width, height) / radius;
  const [cy, sy, cp, sp] = [Math.cos(view.yaw), Math.sin(view.yaw), Math.cos(view.pitch), Math.sin(view.pitch)];
  // Screen right, screen up and depth (away from the eye) of a vector.
  const project = ([x, y, z]) => {
    const [u, w] = [x * cy - y * sy, x * sy + y * cy];
    return [u, z * cp + w * sp, w * cp - z * sp];
  };
  const screen = Array.from({ length: n }, (_, i) => project(c.position[i].map((v, k) => v - centre[k])));
  const { values, lo, hi, uniform } = fieldValues(c, field);
  const order = Array.from({ length: n }, (_, i) => i).sort((a, b) => screen[b][2] - screen[a][2]);
  ctx.clearRect(0, 0, width, height);
  const h = grid.cell_size;
  for (const i of order) {
    const volume = c.volume && c.volume.length ? c.volume[i] : (h * h * h) / 8;
    const s = Math.max(2, 0.5 + scale * Math.cbrt(volume));
    ctx.fillStyle = colour((values[i] - lo) / (hi - lo));
    ctx.fillRect(width / 2 + scale * screen[i][0] - s / 2, height / 2 - scale * screen[i][1] - s / 2, s, s);
  }
  const cells = drawSurfaces(ctx, doc.boundaries || [], (x) => {
    const [u, v, d] = project(x.map((value, k) => value - centre[k]));
    return [width / 2 + scale * u, height / 2 - scale * v, d];
  });
  // The axes, from a corner.
  const [ax, ay, arm] = [40, height - 40, 26];
  ctx.lineWidth = 2;
  ctx.font = '12px sans-serif';
  [['x', [1, 0, 0], '#d00'], ['y', [0, 1, 0], '#080'], ['z', [0, 0, 1], '#00c']].forEach(([name, e, ink]) => {
    const [u, v] = project(e);
    ctx.strokeStyle = ink;
    ctx.fillStyle = ink;
    ctx.beginPath();
    ctx.moveTo(ax, ay);
    ctx.lineTo(ax + arm * u, ay - arm * v);
    ctx.stroke();
    ctx.fillText(name, ax + (arm + 6) * u - 3, ay - (arm + 6) * v + 4);
  });
  // A scale bar of one cell, in the other corner.
  ctx.fillStyle = '#222';
  ctx.fillRect(width - 12 - h * scale, height - 14, h * scale, 3);
  ctx.textAlign = 'right';
  ctx.fillText(`h = ${h} m`, width - 12, height - 20);
  ctx.textAlign = 'start';
  canvas.dataset.points = n;
  canvas.dataset.curves = cells;
  canvas.dataset.view = `${view.yaw.toFixed(3)},${view.pitch.toFixed(3)}`;
  return { points: n, curves: cells, range: [lo, hi], uniform };
}

// Draws over the points the cells of a 3D job's surfaces that face the
// eye: each cell's four edges are cubic Beziers whose control points are
// rows of its patch's net, and an orthographic view maps a Bezier to the
// Bezier of the mapped control points, so the edges drawn are exact.
// `toScreen` gives a point's canvas x, y and depth. Returns the cells drawn.
function drawSurfaces(ctx, surfaces, toScreen) {
  let drawn = 0;
  ctx.lineWidth = 1;
  ctx.strokeStyle = 'rgba(20, 20, 20, 0.45)';
  for (const s of surfaces) {
    const [cu, cv] = s.cells;
    const nu = 3 * cu + 1;
    const at = (i, j) => toScreen(s.control_points[i + nu * j]);
    for (let l = 0; l < cv; l++) {
      for (let k = 0; k < cu; k++) {
        const [i, j] = [3 * k, 3 * l];
        const [p00, p30, p03] = [at(i, j), at(i + 3, j), at(i, j + 3)];
        // Outward normal's sign on the screen: the cell faces the eye when
        // its corners turn clockwise in canvas coordinates (y down).
        const turn = (p30[0] - p00[0]) * (p03[1] - p00[1]) - (p30[1] - p00[1]) * (p03[0] - p00[0]);
        if (turn >= 0) continue;
        ctx.beginPath();
        ctx.moveTo(p00[0], p00[1]);
        for (const [a, b, c] of [
          [at(i + 1, j), at(i + 2, j), p30],
          [at(i + 3, j + 1), at(i + 3, j + 2), at(i + 3, j + 3)],
          [at(i + 2, j + 3), at(i + 1, j + 3), p03],
          [at(i, j + 2), at(i, j + 1), p00],
        ]) ctx.bezierCurveTo(a[0], a[1], b[0], b[1], c[0], c[1]);
        ctx.stroke();
        drawn += 1;
      }
    }
  }
  return drawn;
}

function drawColourBar(bar, labels, field, [lo, hi], uniform = null) {
  bar.hidden = !field;
  if (!field) {
    labels.replaceChildren(el('div', {}, 'no field stored to colour by (output.fields)'));
    return;
  }
  const ctx = bar.getContext('2d');
  for (let y = 0; y < bar.height; y++) {
    ctx.fillStyle = colour(1 - y / (bar.height - 1));
    ctx.fillRect(0, y, bar.width, 1);
  }
  if (uniform !== null) {
    labels.replaceChildren(
      el('div', {}, `${field.label} (${field.unit})`),
      el('div', {}, `${formatNumber(uniform)} everywhere`));
    return;
  }
  labels.replaceChildren(
    el('div', {}, `${field.label} (${field.unit})`),
    el('div', {}, `max ${formatNumber(hi)}`),
    el('div', {}, `min ${formatNumber(lo)}`));
}

// ---- plots of the result ----

const COLOURS = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#ff7f0e', '#8c564b'];

// A small line plot: series of {label, points: [[x, y]]}.
function linePlot(title, xLabel, yLabel, series, { bars = false, empty = 'no finished steps yet' } = {}) {
  const [W, H, L, R, T, B] = [380, 240, 64, 12, 10, 40];
  const all = series.flatMap((s) => s.points).filter(([x, y]) => Number.isFinite(x) && Number.isFinite(y));
  const node = svg('svg', { width: W, height: H + 18 * series.length, 'font-size': 11, 'font-family': 'sans-serif' });
  const figure = el('figure', { class: 'plot', 'data-title': title }, el('figcaption', {}, title), node);
  if (!all.length) {
    figure.append(el('p', { class: 'note' }, empty));
    return figure;
  }
  // Bars stand on whole numbers with half a unit either side.
  let [xa, xb] = bars
    ? [Math.min(...all.map((p) => p[0])) - 0.5, Math.max(...all.map((p) => p[0])) + 0.5]
    : [Math.min(0, ...all.map((p) => p[0])), Math.max(...all.map((p) => p[0]))];
  let [ya, yb] = [Math.min(0, ...all.map((p) => p[1])), Math.max(0, ...all.map((p) => p[1]))];
  if (xb <= xa) xb = xa + 1;
  if (yb <= ya) yb = ya + 1;
  const px = (x) => L + ((x - xa) / (xb - xa)) * (W - L - R);
  const py = (y) => T + ((yb - y) / (yb - ya)) * (H - T - B);
  node.append(svg('rect', { x: L, y: T, width: W - L - R, height: H - T - B, fill: 'none', stroke: '#888' }));
  for (const [v, at, vertical] of [...ticks(xa, xb).map((v) => [v, px(v), true]), ...ticks(ya, yb).map((v) => [v, py(v), false])]) {
    const text = svg('text', vertical
      ? { x: at, y: H - B + 14, 'text-anchor': 'middle' }
      : { x: L - 4, y: at + 4, 'text-anchor': 'end' });
    text.textContent = formatNumber(v);
    node.append(vertical
      ? svg('line', { x1: at, x2: at, y1: T, y2: H - B, stroke: '#eee' })
      : svg('line', { x1: L, x2: W - R, y1: at, y2: at, stroke: '#eee' }), text);
  }
  const xl = svg('text', { x: (L + W - R) / 2, y: H - 6, 'text-anchor': 'middle' });
  xl.textContent = xLabel;
  const yl = svg('text', { transform: `translate(12 ${(T + H - B) / 2}) rotate(-90)`, 'text-anchor': 'middle' });
  yl.textContent = yLabel;
  node.append(xl, yl);
  series.forEach((s, k) => {
    const stroke = COLOURS[k % COLOURS.length];
    if (bars) {
      const w = Math.max(2, (0.6 * (W - L - R)) / Math.max(1, s.points.length + 1));
      for (const [x, y] of s.points) {
        node.append(svg('rect', { x: px(x) - w / 2, y: py(y), width: w, height: py(ya) - py(y), fill: stroke }));
      }
    } else {
      node.append(svg('polyline', {
        points: s.points.map(([x, y]) => `${px(x)},${py(y)}`).join(' '), fill: 'none', stroke, 'stroke-width': 1.5,
      }));
      for (const [x, y] of s.points) node.append(svg('circle', { cx: px(x), cy: py(y), r: 2.5, fill: stroke }));
    }
    const ly = H + 6 + 18 * k;
    const label = svg('text', { x: L + 22, y: ly + 4 });
    label.textContent = s.label;
    node.append(svg('line', { x1: L, x2: L + 16, y1: ly, y2: ly, stroke, 'stroke-width': 2 }), label);
  });
  return figure;
}

function ticks(lo, hi) {
  const raw = (hi - lo) / 5;
  const magnitude = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * magnitude).find((s) => s >= raw);
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) out.push(Math.abs(v) < 1e-12 * step ? 0 : v);
  return out;
}

function resultPlots(result, kase) {
  const figures = [];
  // A job that has ended will finish no more steps.
  const ended = !['queued', 'running'].includes(result.job.status);
  const empty = ended ? `no step finished (the job ${result.job.status})` : 'no finished steps yet';
  // A staged case's load factor runs over each stage: plot against the step.
  const staged = result.reactions.some((r) => r.stage);
  const [xLabel, x] = staged ? ['load step', (s) => s.step] : ['load factor', (s) => s.load_factor];
  for (const [name, samples] of Object.entries(result.probes)) {
    figures.push(linePlot(`probe ${name}`, xLabel, 'displacement (m)', [
      { label: 'u_x', points: samples.map((s) => [x(s), s.displacement[0]]) },
      { label: 'u_y', points: samples.map((s) => [x(s), s.displacement[1]]) },
    ], { empty }));
  }
  const supports = staged ? [] : (kase.supports || []);
  const count = Math.max(0, ...result.reactions.map((r) => r.supports.length));
  // Reactions of three components in 3D, forces rather than per unit thickness.
  const dimension = result.reactions.length ? result.reactions[0].applied_load.length : 2;
  if (count) {
    const series = [];
    for (let j = 0; j < count; j++) {
      const name = supports[j] ? `support ${j} (${supports[j].fix})` : `support ${j}`;
      for (const [c, axis] of [[0, 'F_x'], [1, 'F_y'], [2, 'F_z']].slice(0, dimension)) {
        const points = result.reactions.filter((r) => j < r.supports.length).map((r) => [x(r), r.supports[j][c]]);
        series.push({ label: `${name} ${axis}`, points });
      }
    }
    const unit = dimension === 3 ? 'force (N)' : 'force per unit thickness (N/m)';
    figures.push(linePlot('reactions', xLabel, unit, series, { empty }));
  }
  figures.push(linePlot('Newton iterations per step', 'load step', 'iterations',
    [{ label: 'iterations', points: result.newton.filter((s) => s.step > 0).map((s) => [s.step, s.iterations]) }], { bars: true, empty }));
  return figures;
}

// ---- start ----

// "forget token" only while there is one to forget.
const forgetToken = document.getElementById('forget-token');
const showForgetToken = () => { forgetToken.hidden = !sessionStorage.getItem(TOKEN_KEY); };
forgetToken.addEventListener('click', () => {
  sessionStorage.removeItem(TOKEN_KEY);
  showForgetToken();
  route();
});
window.addEventListener('hashchange', route);
window.addEventListener('hashchange', showForgetToken);
document.getElementById('token-form').addEventListener('submit', () => setTimeout(showForgetToken));
showForgetToken();
route();
