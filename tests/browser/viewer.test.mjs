// End-to-end tests of the viewer in headless Chromium: starts `mpm serve`
// with a token on a throwaway database, solves the paper's cantilever and a
// case that fails, and drives the page as a user would.
//
//   node viewer.test.mjs                     # target/debug/mpm, /usr/bin/chromium
//   MPM_BIN=... CHROMIUM=... SCREENSHOT=docs/viewer.png node viewer.test.mjs
//   SCREENSHOT_3D=docs/viewer-sphere3d.png node viewer.test.mjs  # runs sphere3d too

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createInterface } from 'node:readline';
import { chromium } from 'playwright-core';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const mpm = process.env.MPM_BIN || join(root, 'target/debug/mpm');
const TOKEN = 'viewer-test-token';

let server;
let base;
let dir;
let browser;
const jobs = {};

async function call(method, path, body) {
  const response = await fetch(base + path, {
    method,
    headers: { Authorization: `Bearer ${TOKEN}`, 'Content-Type': 'application/json' },
    body: body && JSON.stringify(body),
  });
  assert.ok(response.ok, `${method} ${path}: HTTP ${response.status} ${await response.clone().text()}`);
  return response.json();
}

async function until(what, check, seconds = 120) {
  const end = Date.now() + seconds * 1000;
  for (;;) {
    const value = await check();
    if (value) return value;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}`);
    await new Promise((r) => setTimeout(r, 200));
  }
}

before(async () => {
  assert.ok(existsSync(mpm), `${mpm} is missing: build it first (cargo build)`);
  dir = mkdtempSync(join(tmpdir(), 'mpm-viewer-'));
  server = spawn(mpm, ['serve', '--addr', '127.0.0.1:0', '--token', TOKEN,
    '--database', join(dir, 'jobs.sqlite'), '--workers', '2'], { stdio: ['ignore', 'pipe', 'inherit'] });
  const firstLine = await new Promise((ok, fail) => {
    createInterface({ input: server.stdout }).once('line', ok);
    server.once('exit', (code) => fail(new Error(`mpm serve exited with ${code}`)));
  });
  base = firstLine.match(/http:\/\/\S+/)[0];

  const cantilever = JSON.parse(execFileSync(mpm, ['example', 'cantilever']));
  const failing = structuredClone(cantilever);
  failing.title = 'cantilever allowed two Newton iterations a step';
  failing.analysis.newton = { max_iterations: 2 };
  const stillborn = structuredClone(cantilever);
  stillborn.title = 'cantilever of E = 1 Pa, failing in its first step';
  stillborn.bodies[0].material.youngs_modulus = 1;
  const thinned = structuredClone(cantilever);
  thinned.title = 'cantilever storing the points of every second step, no columns';
  thinned.output = { every: 2, fields: [] };
  // The cantilever in two stages: half its pressure, then the rest.
  const staged = structuredClone(cantilever);
  staged.title = 'cantilever loaded in two stages';
  const { loads, supports } = staged;
  delete staged.loads;
  delete staged.supports;
  delete staged.analysis.load_steps;
  const half = loads.boundary.map((l) => ({ ...l, pressure: l.pressure / 2 }));
  staged.stages = [
    { name: 'half', load_steps: 2, supports, loads: { boundary: half } },
    { name: 'whole', load_steps: 2, loads },
  ];
  // A von Mises block loaded to its plane-strain strength over 1.23, then
  // reduced: its factor of safety is 1.23.
  const flow = (2 * 1e3) / Math.sqrt(3);
  const reduced = {
    version: 1,
    title: 'von Mises block loaded, then its strength reduced',
    analysis: {},
    grid: { cell_size: 0.25, origin: [0, 0] },
    bodies: [{
      geometry: { rectangle: { min: [0, 0], max: [1, 1] } },
      points: { per_cell: 2 },
      material: { model: 'von_mises', youngs_modulus: 1e6, poisson_ratio: 0.3, density: 0, yield_stress: 1e3 },
    }],
    stages: [
      { load_steps: 2, loads: { boundary: [{ on: { y: 1 }, pressure: flow / 1.23 }] },
        supports: [{ on: { x: 0 }, fix: 'x' }, { on: { y: 0 }, fix: 'y' }] },
      { load_steps: 20, strength_reduction: { increment: 0.1, tolerance: 0.01 } },
    ],
  };
  jobs.column3d = (await call('POST', '/jobs', JSON.parse(execFileSync(mpm, ['example', 'column3d'])))).id;
  if (process.env.SCREENSHOT_3D) {
    jobs.sphere3d = (await call('POST', '/jobs', JSON.parse(execFileSync(mpm, ['example', 'sphere3d'])))).id;
  }
  jobs.reduced = (await call('POST', '/jobs', reduced)).id;
  jobs.cantilever = (await call('POST', '/jobs', cantilever)).id;
  jobs.staged = (await call('POST', '/jobs', staged)).id;
  jobs.failing = (await call('POST', '/jobs', failing)).id;
  jobs.thinned = (await call('POST', '/jobs', thinned)).id;
  jobs.stillborn = (await call('POST', '/jobs', stillborn)).id;
  for (const id of Object.values(jobs)) {
    await until(`job ${id} to end`, async () => {
      const job = await call('GET', `/jobs/${id}`);
      return job.status !== 'queued' && job.status !== 'running';
    });
  }
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox'],
  });
});

after(async () => {
  await browser?.close();
  server?.kill('SIGTERM');
  if (dir) rmSync(dir, { recursive: true, force: true });
});

// Pixel statistics of the points canvas: drawn (not blank) pixels and
// boundary-red ones.
async function canvasStatistics(page) {
  return page.$eval('#points', (canvas) => {
    const { data } = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height);
    let drawn = 0;
    let red = 0;
    for (let i = 0; i < data.length; i += 4) {
      if (data[i + 3] === 0) continue;
      drawn++;
      if (data[i] > 180 && data[i + 1] < 60 && data[i + 2] < 60) red++;
    }
    return { drawn, red, pixels: canvas.width * canvas.height, image: canvas.toDataURL() };
  });
}

async function signedIn(page) {
  await page.goto(base + '/');
  await page.waitForSelector('#token-form:not([hidden])');
  await page.fill('#token-input', TOKEN);
  await page.click('#token-form button[type=submit]');
}

test('the page asks for the token, refuses a wrong one and lists the jobs with the right one', async () => {
  const page = await browser.newPage();
  await page.goto(base + '/');
  await page.waitForSelector('#token-form:not([hidden])');
  // Nothing to forget yet.
  assert.equal(await page.$eval('#forget-token', (b) => b.hidden), true);
  await page.fill('#token-input', 'wrong');
  await page.click('#token-form button[type=submit]');
  await page.waitForSelector('#token-error:not([hidden])');
  await page.fill('#token-input', TOKEN);
  await page.click('#token-form button[type=submit]');
  await page.waitForSelector(`tr[data-job="${jobs.failing}"]`);
  const rows = await page.$$eval('tr[data-job]', (trs) => trs.map((tr) => [tr.dataset.job, tr.querySelector('.status').textContent]));
  assert.deepEqual(Object.fromEntries(rows), {
    [jobs.cantilever]: 'succeeded',
    [jobs.staged]: 'succeeded',
    [jobs.failing]: 'failed',
    [jobs.thinned]: 'succeeded',
    [jobs.stillborn]: 'failed',
    [jobs.reduced]: 'succeeded',
    [jobs.column3d]: 'succeeded',
  });
  assert.equal(await page.$eval('#forget-token', (b) => b.hidden), false);
  // The token is kept for the tab: a reload goes straight to the list.
  await page.reload();
  await page.waitForSelector(`tr[data-job="${jobs.cantilever}"]`);
  await page.close();
});

test('a finished job shows its body, boundary, slider, fields and plots', async () => {
  const page = await browser.newPage({ viewport: { width: 1280, height: 1100 } });
  await signedIn(page);
  await page.click(`a[href="#/jobs/${jobs.cantilever}"]`);
  await page.waitForSelector('#points[data-points="896"]');
  assert.equal(await page.$eval('#step-slider', (s) => s.max), '5');
  assert.equal(await page.$eval('#step-slider', (s) => s.value), '5');
  assert.equal(await page.$eval('#points', (c) => c.dataset.curves), '1');

  const last = await canvasStatistics(page);
  // 896 points of a 10 m x 2 m beam fill a good part of the frame.
  assert.ok(last.drawn > 0.1 * last.pixels, `only ${last.drawn} of ${last.pixels} pixels drawn`);
  assert.ok(last.red > 500, `the boundary curve drew only ${last.red} red pixels`);
  assert.match(await page.textContent('#step-label'), /step 5 of 5, load factor 1/);
  assert.match(await page.textContent('.summary'), /cell size h = 1\.5 m/);
  // The paper's bilinear basis, bent past its cells: the page says what
  // that does to the answer.
  await page.waitForSelector('.job-warnings:not([hidden])');
  assert.match(await page.textContent('.job-warnings'), /^bilinear_crossing: \d+ points left the cell they started in/);

  // Step 0: the undeformed beam, drawn differently.
  await page.$eval('#step-slider', (s) => { s.value = 0; s.dispatchEvent(new Event('input')); });
  await page.waitForFunction(() => document.querySelector('#step-label').textContent.startsWith('step 0 of 5, load factor 0'));
  await page.waitForSelector('#points[data-points="896"]');
  const first = await canvasStatistics(page);
  assert.notEqual(first.image, last.image, 'steps 0 and 5 draw the same picture');
  assert.ok(first.red > 500);

  // Colour by a stress component: the colour bar names it with its unit.
  await page.$eval('#step-slider', (s) => { s.value = 3; s.dispatchEvent(new Event('input')); });
  await page.waitForFunction(() => document.querySelector('#step-label').textContent.startsWith('step 3 of 5'));
  await page.selectOption('#field', 'sxx');
  await page.waitForFunction(() => document.querySelector('.legend').textContent.includes('stress σ_xx (Pa)'));
  const options = await page.$$eval('#field option', (os) => os.map((o) => o.value));
  for (const f of ['u', 'ux', 'uy', 'sxx', 'syy', 'sxy', 'szz', 'J', 'ep']) assert.ok(options.includes(f), `no field ${f}`);

  // Plots: the tip probe and two supports' reactions at steps 0 to 5, and
  // a bar per load step of Newton iterations.
  const plots = await page.$$eval('figure.plot', (fs) => fs.map((f) => [f.dataset.title, f.querySelectorAll('circle').length, f.querySelectorAll('rect').length - 1]));
  const byTitle = Object.fromEntries(plots.map(([t, circles, bars]) => [t, { circles, bars }]));
  assert.equal(byTitle['probe tip'].circles, 2 * 6);
  assert.equal(byTitle.reactions.circles, 2 * 2 * 6);
  assert.equal(byTitle['Newton iterations per step'].bars, 5);

  // The archive downloads with the token.
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#download')]);
  assert.equal(download.suggestedFilename(), `job-${jobs.cantilever}.zip`);
  const zip = await download.path();
  assert.ok(zip && (await import('node:fs')).statSync(zip).size > 10000, 'the archive is nearly empty');

  if (process.env.SCREENSHOT) {
    await page.selectOption('#field', 'u');
    await page.$eval('#step-slider', (s) => { s.value = 5; s.dispatchEvent(new Event('input')); });
    await page.waitForFunction(() => document.querySelector('#step-label').textContent.startsWith('step 5 of 5'));
    await page.screenshot({ path: process.env.SCREENSHOT, fullPage: true });
  }
  await page.close();
});

test('a failed job shows its error with step, iteration and residual', async () => {
  const page = await browser.newPage();
  await signedIn(page);
  await page.click(`a[href="#/jobs/${jobs.failing}"]`);
  await page.waitForSelector('.job-error:not([hidden])');
  const text = await page.textContent('.job-error');
  assert.match(text, /^failed: /);
  assert.match(text, /\(step \d, iteration 2, residual \d\.\d+e-\d+\)$/);
  // Step 0 was stored before the solve failed: the body is still shown.
  await page.waitForSelector('#points[data-points="896"]');
  await page.close();
});

test('a job that failed in its first step says so, not "min -0.5" and "no finished steps yet"', async () => {
  const page = await browser.newPage();
  await signedIn(page);
  await page.click(`a[href="#/jobs/${jobs.stillborn}"]`);
  await page.waitForSelector('#points[data-points="896"]');
  // Step 0 only: every displacement is 0.
  await page.waitForFunction(() => document.querySelector('.legend').textContent.includes('everywhere'));
  assert.doesNotMatch(await page.textContent('.legend'), /min /);
  await page.waitForSelector('figure.plot');
  const notes = await page.$$eval('figure.plot .note', (ps) => ps.map((p) => p.textContent));
  assert.ok(notes.length > 0 && notes.every((n) => n === 'no step finished (the job failed)'), notes.join('; '));
  await page.close();
});

test('a job that stores no columns and thins its steps still shows its body', async () => {
  const page = await browser.newPage();
  await signedIn(page);
  await page.click(`a[href="#/jobs/${jobs.thinned}"]`);
  await page.waitForSelector('#points[data-points="896"]');
  assert.match(await page.textContent('.legend'), /no field stored to colour by/);
  const drawn = await canvasStatistics(page);
  assert.ok(drawn.red > 500, 'no boundary drawn');
  // Step 3 kept no points (every 2); step 4 did.
  await page.$eval('#step-slider', (s) => { s.value = 3; s.dispatchEvent(new Event('input')); });
  await page.waitForFunction(() => document.querySelector('#step-note').textContent.includes('not stored'));
  assert.equal(await page.$eval('#points', (c) => c.dataset.points), '0');
  await page.$eval('#step-slider', (s) => { s.value = 4; s.dispatchEvent(new Event('input')); });
  await page.waitForSelector('#points[data-points="896"]');
  await page.close();
});

test('a strength-reduction job says the factor of each step and which is the factor of safety', async () => {
  const page = await browser.newPage();
  await signedIn(page);
  await page.click(`a[href="#/jobs/${jobs.reduced}"]`);
  await page.waitForSelector('#points[data-points="64"]');
  const label = await page.textContent('#step-label');
  const [, factor] = label.match(/strength factor ([\d.]+) \(the factor of safety\)$/) || [];
  assert.ok(factor && Number(factor) > 1.21 && Number(factor) <= 1.23, label);
  await page.$eval('#step-slider', (s) => { s.value = 3; s.dispatchEvent(new Event('input')); });
  await page.waitForFunction(() => /strength factor 1\.1$/.test(document.querySelector('#step-label').textContent));
  await page.close();
});

test('a staged job names the stage of each step and plots against the step', async () => {
  const page = await browser.newPage();
  await signedIn(page);
  await page.click(`a[href="#/jobs/${jobs.staged}"]`);
  await page.waitForSelector('#points[data-points="896"]');
  assert.match(await page.textContent('#step-label'), /step 4 of 4, stage "whole", load factor 1/);
  await page.$eval('#step-slider', (s) => { s.value = 2; s.dispatchEvent(new Event('input')); });
  await page.waitForFunction(() => document.querySelector('#step-label').textContent.startsWith('step 2 of 4, stage "half", load factor 1'));
  const axes = await page.$$eval('figure.plot', (fs) => fs.map((f) => [f.dataset.title, f.textContent]));
  const reactions = axes.find(([t]) => t === 'reactions');
  assert.ok(reactions && reactions[1].includes('load step'), 'the reactions run by step');
  await page.close();
});

test('a 3D job is drawn in a view that turns when dragged', async () => {
  const page = await browser.newPage({ viewport: { width: 1280, height: 1100 } });
  await signedIn(page);
  await page.click(`a[href="#/jobs/${jobs.column3d}"]`);
  await page.waitForSelector('#points[data-points="128"]');
  assert.equal(await page.$eval('#step-slider', (s) => s.max), '40');
  assert.match(await page.textContent('#step-note'), /128 points drawn in 3D/);
  // The 3D fields: three displacements and six stresses.
  const fields = await page.$$eval('#field option', (os) => os.map((o) => o.value));
  for (const key of ['uz', 'szz', 'syz', 'sxz']) assert.ok(fields.includes(key), `${key} in ${fields}`);
  await page.selectOption('#field', 'szz');
  const start = await canvasStatistics(page);
  // The column, squashed to half its height, still shows as a body.
  assert.ok(start.drawn > 0.01 * start.pixels, `only ${start.drawn} of ${start.pixels} pixels drawn`);
  const first = await page.$eval('#points', (c) => c.dataset.view);
  // Its surface over the points: of the box's 414 Bezier cells (two faces
  // of 3 x 33 cells along each side, two of 3 x 3 across), those of the
  // three faces that face the eye, two sides and the top.
  assert.equal(await page.$eval('#points', (c) => c.dataset.curves), '207');

  // A drag turns the view, and draws another picture; a double click
  // brings the first view back.
  const box = await (await page.$('#points')).boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 + 120, box.y + box.height / 2 + 40, { steps: 5 });
  await page.mouse.up();
  await page.waitForFunction((v) => document.querySelector('#points').dataset.view !== v, first);
  const turned = await canvasStatistics(page);
  assert.notEqual(turned.image, start.image, 'the drag left the picture as it was');
  await page.dblclick('#points');
  await page.waitForFunction((v) => document.querySelector('#points').dataset.view === v, first);
  // The reactions plot has z components, in N.
  const plots = await page.$$eval('figure.plot', (fs) => fs.map((f) => f.textContent));
  assert.ok(plots.some((t) => /F_z/.test(t) && /force \(N\)/.test(t)), plots.join(' | '));
  if (process.env.SCREENSHOT_3D) {
    await until('the sphere', async () => (await call('GET', `/jobs/${jobs.sphere3d}`)).status === 'succeeded', 600);
    await page.goto(`${base}/#/jobs/${jobs.sphere3d}`);
    await page.waitForSelector('#points[data-points="3674"]');
    await page.selectOption('#field', 'u');
    await (await page.$('#points')).screenshot({ path: process.env.SCREENSHOT_3D });
  }
  await page.close();
});
