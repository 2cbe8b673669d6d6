// Benchmark (not a test): playback over the protocol alone, loop after loop, as the UI plays
// (web/src/playback.ts): at each step's due time the newest frame of the step sent ahead is shown
// and the step after it is sent as a step of playback with the period, less the transport, as its
// time budget; a step whose frame has not come is shown when it comes and the schedule starts again
// from then. Prints per loop: steps/s, and the frames shown at level 0 and full size, and from the
// frames rendered ahead ("cached": docs/protocol.md, "Frames rendered ahead").
//   node --experimental-websocket bench/playback_loops.mjs RAYPC DATASET [--fps 2] [--loops 3]
//        [--size 1500x627] [--pause S] [-- extra serve options...]
// --pause S: after the still frame of step 0, wait S seconds (paused) before playing (default 0).
import { openSession, startServer } from './protocol_client.mjs';
import { readFileSync } from 'node:fs';

const args = process.argv.slice(2);
const dash = args.indexOf('--');
const serveExtra = dash < 0 ? [] : args.splice(dash).slice(1);
const flag = (name, fallback) => { const i = args.indexOf(name); return i < 0 ? fallback : args.splice(i, 2)[1]; };
const fps = Number(flag('--fps', '2')), loops = Number(flag('--loops', '3')), pauseS = Number(flag('--pause', '0'));
const [width, height] = flag('--size', '1500x627').split('x').map(Number);
const [raypc, dataset] = args;
if (!raypc || !dataset || typeof WebSocket !== 'function') {
  console.error('usage: node --experimental-websocket bench/playback_loops.mjs RAYPC DATASET [--fps 2] [--loops 3] [--size WxH] [--pause S] [-- serve options]');
  process.exit(2);
}
const { child, url, info } = await startServer(raypc, dataset, serveExtra);
const nSteps = info.steps.length;
const base = { ...info.defaultState, image: { width, height } };

const ws = await openSession(url);
const newest = new Map(); // state id -> { header, at }
let onFrame = () => {};
ws.onmessage = (e) => {
  if (typeof e.data === 'string') return;
  const n = new DataView(e.data).getUint32(0, true);
  const h = JSON.parse(new TextDecoder().decode(new Uint8Array(e.data, 4, n)));
  newest.set(h.id, { header: h, at: performance.now() });
  onFrame(h);
};
const frameOf = (id) => new Promise((resolve) => {
  if (newest.has(id)) return resolve(newest.get(id));
  onFrame = (h) => { if (h.id === id) resolve(newest.get(id)); };
});
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, Math.max(0, ms)));

let id = 0;
ws.send(JSON.stringify({ type: 'state', id: ++id, state: { ...base, step: 0 } }));
await new Promise((resolve) => { onFrame = (h) => { if (h.id === id && h.converged) resolve(); }; });
await sleep(pauseS * 1000);

const period = 1000 / fps;
let transport = 40;
const send = (step) => {
  const budget = Math.max(1, period - Math.min(transport, period / 2));
  ws.send(JSON.stringify({ type: 'state', id: ++id, state: { ...base, step, timeBudgetMs: budget }, playback: true }));
  return { step, id, sentAt: performance.now() };
};
const shown = []; // { loop, step, level, width, height, pass, cached, t }
let ahead = send(1 % nSteps);
let due = performance.now() + period;
const total = loops * nSteps;
for (let k = 1; k <= total; k++) {
  await sleep(due - performance.now());
  const f = await frameOf(ahead.id);
  const h = f.header;
  if (h.pass === 1) transport = 0.7 * transport + 0.3 * Math.max(0, f.at - ahead.sentAt - (h.stats?.passMs ?? 0));
  const now = performance.now();
  due = now - due > 0.25 * period ? now + period : due + period;
  shown.push({ loop: Math.floor(k / nSteps), step: ahead.step, level: h.level, width: h.width, height: h.height,
    pass: h.pass, passes: h.passes, converged: h.converged === true, cached: h.cached === true, t: now });
  ahead = send((ahead.step + 1) % nSteps);
}
ws.close();
child.kill('SIGTERM');
await new Promise((resolve) => child.once('exit', resolve));

console.log(`playback of ${nSteps} steps at ${fps} steps/s asked, ${width}x${height}, ${loops} loops (loop 0 starts at step 1)`);
for (let l = 0; l <= loops; l++) {
  const s = shown.filter((x) => x.loop === l);
  if (s.length < 2) continue;
  const rate = (s.length - 1) / ((s.at(-1).t - s[0].t) / 1000);
  const full = s.filter((x) => x.level === 0 && x.width === width && x.height === height).length;
  const levels = {};
  for (const x of s) levels[x.level] = (levels[x.level] ?? 0) + 1;
  // With every pass: the last frame of its state and more than its first pass (adaptive refinement
  // stops a frame early only after its second pass); a draft or a one-pass step says converged
  // after its first pass of several.
  const done = s.filter((x) => x.level === 0 && x.width === width && x.height === height && x.converged &&
    (x.pass > 1 || x.passes === 1)).length;
  console.log(`  loop ${l + 1}: ${s.length} steps shown at ${rate.toFixed(2)} steps/s; level 0 at full size ${full}/${s.length} ` +
    `(${(100 * full / s.length).toFixed(0)} %), of which with every pass ${done}; from the frames rendered ahead ` +
    `${s.filter((x) => x.cached).length}; by level ${JSON.stringify(levels)}`);
}
console.log(`load: ${readFileSync('/proc/loadavg', 'utf8').trim()}`);
process.exit(0);
