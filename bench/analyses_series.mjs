// Benchmark (not a test): the UI's analyses over a series (issue 48, item 4; docs/scaling.md, "Kept
// analyses"). Synthesises N steps (`raypc synth`, a slab avalanche through 660 km), preprocesses them
// without pathlines, serves the dataset and times, as the UI asks them:
//   statistics of a new brush     POST /api/stats?profiles=all (level 1, the panel's default; with
//                                 --exact also level 0)
//   the same after a step change  (the UI no longer asks: what it would cost if it did)
//   features of a new brush       POST /api/features (the state's features.level)
//   the same after a step change  and with the painting turned on
// each with the steps the server computed (X-Raypc-Steps-Computed), per step, the answer's size and
// hash (the same answer from any number of ranks) and the load.
// Goal at 24 full-resolution steps (--full): statistics of a new brush <= 1 s, features <= 8 s, both
// <= 2 s when only the step changes.
//   node bench/analyses_series.mjs [BUILD_DIR] [--steps N] [--grid LATxRxLON | --full] [--exact]
//        [--work DIR] [--keep] [--dataset DIR] [--ranks N]
// --dataset times an existing dataset instead (bench/series.sh passes the one it preprocessed);
// --steps and --grid are then taken from it.
// Defaults: build/, 12 steps, 64x81x128 (the demo's grid), ${TMPDIR:-/tmp}/raypc-bench-analyses.
import { execFileSync, spawn } from 'node:child_process';
import { createHash } from 'node:crypto';
import { cpus } from 'node:os';
import { readFileSync, rmSync, readdirSync } from 'node:fs';
import { join, resolve } from 'node:path';

const args = process.argv.slice(2);
const flag = (name) => { const i = args.indexOf(name); if (i < 0) return false; args.splice(i, 1); return true; };
const option = (name, fallback) => {
  const i = args.indexOf(name);
  if (i < 0) return fallback;
  const v = args[i + 1];
  args.splice(i, 2);
  return v;
};
const full = flag('--full'), exact = flag('--exact'), keep = flag('--keep');
const given = option('--dataset', undefined);
const ranks = Number(option('--ranks', '1'));
let steps = Number(option('--steps', '12'));
const grid = option('--grid', full ? '180x201x360' : '64x81x128');
const work = resolve(option('--work', join(process.env.TMPDIR ?? '/tmp', 'raypc-bench-analyses')));
const build = resolve(args[0] ?? 'build');
if (!Number.isInteger(steps) || steps < 2 || !/^\d+x\d+x\d+$/.test(grid) || !Number.isInteger(ranks) || ranks < 1 ||
    args.length > 1) {
  console.error('usage: node bench/analyses_series.mjs [BUILD_DIR] [--steps N>=2] [--grid LATxRxLON | --full] [--exact] [--work DIR] [--keep] [--dataset DIR] [--ranks N]');
  process.exit(2);
}
const raypc = join(build, 'raypc');
const load = () => readFileSync('/proc/loadavg', 'utf8').split(' ').slice(0, 3).join(' ');
const seconds = (t0) => (performance.now() - t0) / 1000;

let dataset = given && resolve(given);
if (dataset) {
  const manifest = JSON.parse(readFileSync(join(dataset, 'dataset.json'), 'utf8'));
  steps = manifest.steps?.length ?? manifest.times?.length ?? NaN;
  console.log(`analyses over ${dataset}: ${steps} steps; machine: ${cpus().length} cores, ${cpus()[0]?.model ?? '?'}`);
} else {
  console.log(`analyses over a series: ${steps} steps of ${grid}; machine: ${cpus().length} cores, ${cpus()[0]?.model ?? '?'}`);
  rmSync(work, { recursive: true, force: true });
  let t0 = performance.now();
  execFileSync(raypc, ['synth', '-o', join(work, 'nc'), '--grid', grid, '--steps', String(steps),
    '--avalanche', String(2 * Math.floor(steps / 2))], { stdio: 'ignore' });
  console.log(`synth:      ${seconds(t0).toFixed(1)} s (load ${load()})`);
  t0 = performance.now();
  const files = readdirSync(join(work, 'nc')).filter((f) => f.endsWith('.nc')).map((f) => join(work, 'nc', f));
  execFileSync(raypc, ['preprocess', ...files, '-o', join(work, 'ds'), '--no-pathlines', '--quiet'], { stdio: 'ignore' });
  console.log(`preprocess: ${seconds(t0).toFixed(1)} s (--no-pathlines; load ${load()})`);
  dataset = join(work, 'ds');
}

// --ranks N: a distributed server (scripts/mpirun-local.sh), which shares the features' steps out.
const serve = ['serve', dataset, '--port', '0'];
const child = ranks > 1
  ? spawn(join(import.meta.dirname, '..', 'scripts', 'mpirun-local.sh'), ['-np', String(ranks), raypc, ...serve],
    { stdio: ['ignore', 'pipe', 'pipe'] })
  : spawn(raypc, serve, { stdio: ['ignore', 'pipe', 'pipe'] });
if (ranks > 1) console.log(`server: ${ranks} ranks`);
let out = '';
const url = await new Promise((res, rej) => {
  child.stdout.on('data', (d) => {
    out += d;
    const m = /serving (http:\/\/\S+)/.exec(out);
    if (m) res(m[1]);
  });
  child.stderr.on('data', () => {});
  child.once('exit', (code) => rej(new Error(`raypc serve exited with ${code}`)));
});
const info = await (await fetch(url + 'api/info')).json();
const anomaly = info.variables.find((v) => v.name === 'temperature anomaly');
if (!anomaly) throw new Error('the dataset has no temperature anomaly');

// Slabs (cold) and plumes (hot) below the lithosphere: two brushes as a user would set them.
const brushes = [
  [{ name: 'temperature anomaly', min: anomaly.min, max: 0.35 * anomaly.min }, { name: 'depth', min: 200, max: 2800 }],
  [{ name: 'temperature anomaly', min: 0.35 * anomaly.max, max: anomaly.max }, { name: 'depth', min: 200, max: 2800 }],
];
const stateOf = (b, step, paint = false) => ({
  ...info.defaultState, step, brushes: b,
  features: { ...info.defaultState.features, colorById: paint },
});
async function ask(path, state) {
  const t = performance.now();
  const r = await fetch(url + path, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state) });
  const body = await r.text();
  if (!r.ok) throw new Error(`${path}: ${r.status} ${body}`);
  return { s: seconds(t), computed: r.headers.get('x-raypc-steps-computed'), bytes: body.length,
    hash: createHash('sha256').update(body).digest('hex').slice(0, 12) };
}
const rows = [];
const row = (what, a) => {
  rows.push(a);
  console.log(`${what.padEnd(46)} ${a.s.toFixed(3).padStart(8)} s  ${(1000 * a.s / steps).toFixed(1).padStart(7)} ms/step` +
    `  computed ${String(a.computed).padStart(3)} of ${steps} steps  ${(a.bytes / 1024).toFixed(0).padStart(6)} KiB  sha256 ${a.hash}  load ${load()}`);
};
const mid = Math.floor(steps / 2);
const levels = exact ? ['', 'level=0&'] : [''];
for (const [i, b] of brushes.entries()) {
  for (const lv of levels) {
    const name = lv ? 'level 0' : 'level 1';
    row(`statistics (${name}), new brush ${i + 1}`, await ask(`api/stats?${lv}profiles=all`, stateOf(b, 0)));
    row(`statistics (${name}), step change`, await ask(`api/stats?${lv}profiles=all`, stateOf(b, mid)));
  }
  row(`features (level ${info.defaultState.features.level}), new brush ${i + 1}`, await ask('api/features', stateOf(b, 0)));
  row('features, step change and painting', await ask('api/features', stateOf(b, mid, true)));
}
child.kill('SIGTERM');
await new Promise((res) => child.once('exit', res));
if (!keep && !given) rmSync(work, { recursive: true, force: true });
console.log(`load at the end: ${load()}`);
