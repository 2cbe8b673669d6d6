// Benchmark (not a test): how long a step change takes over the protocol, from the state message of
// a new step to its converged level-0 frame (the frame with "converged": true at level 0 and full
// size), as the UI sends it when a step is chosen (a still state of the default view at another step).
// The steps visited are 0 (to warm up: the process, the grid's shared tables), then 2, 1, 3, … (never
// the step after the one shown, so that the step cache's prefetch of step + 1 does not load it early;
// each visited step is new to the step cache). Run with `-- --frame-cache 0` so that no frame rendered
// ahead answers a step (docs/protocol.md, "Frames rendered ahead").
//   node --experimental-websocket bench/step_change.mjs RAYPC DATASET [--size 1500x627] [--verbose] [-- serve options...]
// --verbose: the server logs its debug timings (raypc -v) to stderr.
// Prints per step change: the time to the first frame (a preview), to the first level-0 frame, to the
// converged level-0 frame, and the passes; then the load.
import { openSession, startServer } from './protocol_client.mjs';
import { readFileSync } from 'node:fs';

const args = process.argv.slice(2);
const dash = args.indexOf('--');
const serveExtra = dash < 0 ? [] : args.splice(dash).slice(1);
const flag = (name, fallback) => { const i = args.indexOf(name); return i < 0 ? fallback : args.splice(i, 2)[1]; };
const [width, height] = flag('--size', '1500x627').split('x').map(Number);
const verbose = args.indexOf('--verbose') >= 0 ? args.splice(args.indexOf('--verbose'), 1).length : 0;
const [raypc, dataset] = args;
if (!raypc || !dataset || typeof WebSocket !== 'function') {
  console.error('usage: node --experimental-websocket bench/step_change.mjs RAYPC DATASET [--size WxH] [-- serve options]');
  process.exit(2);
}
const { child, url, info } = await startServer(raypc, dataset, serveExtra, { verbose: verbose > 0 });
child.once('exit', (code) => { console.error(`raypc serve exited (${code})`); process.exit(1); });
const nSteps = info.steps.length;
const base = { ...info.defaultState, image: { width, height } };

const ws = await openSession(url);
let onFrame = () => {};
ws.onmessage = (e) => {
  if (typeof e.data === 'string') {
    const m = JSON.parse(e.data);
    if (m.type === 'error') console.error(`error: ${m.message}`);
    return;
  }
  const n = new DataView(e.data).getUint32(0, true);
  onFrame(JSON.parse(new TextDecoder().decode(new Uint8Array(e.data, 4, n))), performance.now());
};

let id = 0;
// Sends a still state of `step` and resolves with the times (ms after sending) of its frames.
const change = (step) => new Promise((resolve) => {
  const sent = performance.now();
  const mine = ++id;
  const t = { step, first: null, level0: null, converged: null, pass: 0, cached: false };
  onFrame = (h, at) => {
    if (h.id !== mine) return;
    const ms = at - sent;
    t.first ??= ms;
    const full = h.level === 0 && h.width === width && h.height === height;
    if (full) t.level0 ??= ms;
    if (full && h.converged) {
      t.converged = ms;
      t.pass = h.pass;
      t.cached = h.cached === true;
      resolve(t);
    }
  };
  ws.send(JSON.stringify({ type: 'state', id: mine, state: { ...base, step } }));
});

await change(0);
const order = [];
for (let s = 2; s < nSteps; s += 2) order.push(s);
for (let s = 1; s < nSteps; s += 2) order.push(s);
console.log(`step changes of ${dataset} (${nSteps} steps), ${width}x${height}, serve ${serveExtra.join(' ')}`);
const converged = [];
for (const step of order) {
  const t = await change(step);
  converged.push(t.converged);
  console.log(`  step ${step}: first frame ${t.first.toFixed(0)} ms, first level 0 ${t.level0.toFixed(0)} ms, ` +
    `converged level 0 ${t.converged.toFixed(0)} ms (${t.pass} passes${t.cached ? ', rendered ahead' : ''})`);
}
const mean = converged.reduce((a, b) => a + b, 0) / converged.length;
console.log(`  mean to converged level 0: ${mean.toFixed(0)} ms; load: ${readFileSync('/proc/loadavg', 'utf8').trim()}`);
ws.close();
child.removeAllListeners('exit');
child.kill('SIGTERM');
await new Promise((resolve) => child.once('exit', resolve));
process.exit(0);
