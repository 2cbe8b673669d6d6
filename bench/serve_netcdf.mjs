// Benchmark (not a test): time to the first picture of netCDF files (`raypc serve
// FILE.nc…`). Starts `raypc serve FILES --dataset DIR --port 0` with DIR empty, then measures from the
// start of the process: the "serving" line (the first step preprocessed alone), the first frame and
// the converged frame of the UI's default state at WxH, and the whole series served (GET
// /api/progress says "complete" on the server that replaced the first), then the server's log lines of
// the first step's phases and of the first still. DIR is removed at the end. One file (a tomography
// model, tests/data/emc-layout/write_emc_layout.py --grid 25x181x361) is a series of one step.
//   node --experimental-websocket bench/serve_netcdf.mjs BUILD_DIR DIR WxH FILE.nc…
import { spawn } from 'node:child_process';
import { readFileSync, rmSync } from 'node:fs';
import { join } from 'node:path';

const [build, dir, size, ...files] = process.argv.slice(2);
if (!build || !dir || !/^\d+x\d+$/.test(size ?? '') || files.length < 1 || typeof WebSocket !== 'function') {
  console.error('usage: node --experimental-websocket bench/serve_netcdf.mjs BUILD_DIR DIR WxH FILE.nc…');
  process.exit(2);
}
const [width, height] = size.split('x').map(Number);
rmSync(dir, { recursive: true, force: true });
const start = performance.now();
const since = () => ((performance.now() - start) / 1000).toFixed(2);
const child = spawn(join(build, 'raypc'), ['-v', 'serve', ...files, '--dataset', dir, '--port', '0'],
  { stdio: ['ignore', 'pipe', 'inherit'] });
let out = '';
const url = await new Promise((resolve, reject) => {
  child.stdout.on('data', (d) => {
    out += d;
    const m = /serving (http:\/\/\S+)/.exec(out);
    if (m) resolve(m[1]);
  });
  child.once('exit', (code) => reject(new Error(`raypc serve exited with ${code}`)));
});
console.log(`serving (step 0 preprocessed):  ${since()} s`);
const info = await (await fetch(url + 'api/info')).json();
const state = { ...info.defaultState, image: { ...info.defaultState.image, width, height } };
const ws = new WebSocket(url.replace(/^http/, 'ws') + 'ws');
ws.binaryType = 'arraybuffer';
await new Promise((resolve) => { ws.onopen = resolve; });
ws.send(JSON.stringify({ type: 'hello', protocol: 1 }));
let first = null;
await new Promise((resolve, reject) => {
  ws.onmessage = (e) => {
    if (typeof e.data === 'string') {
      const m = JSON.parse(e.data);
      if (m.type === 'error') reject(new Error(`the server refused the state: ${m.message ?? e.data}`));
      return;
    }
    const n = new DataView(e.data).getUint32(0, true);
    const h = JSON.parse(new TextDecoder().decode(new Uint8Array(e.data, 4, n)));
    if (first === null) {
      first = since();
      console.log(`first frame (${h.width}x${h.height}, pass ${h.pass}, level ${h.level}): ${first} s`);
    }
    if (h.converged) {
      console.log(`converged frame (pass ${h.pass}):          ${since()} s`);
      resolve();
    }
  };
  // A small series is whole before the first step converges: the server that serves it replaces the
  // first and closes this connection.
  ws.onclose = () => {
    console.log(`connection closed before a converged frame: ${since()} s (the whole series replaced the first step's server)`);
    resolve();
  };
  ws.send(JSON.stringify({ type: 'state', id: 1, state, interactive: false }));
});
ws.onclose = null;
ws.close();
for (;;) {
  let p = null;
  try {
    p = await (await fetch(url + 'api/progress')).json();
  } catch {
    // the server of the whole series is replacing the first
  }
  if (p?.state === 'complete') break;
  if (p?.state === 'failed') throw new Error(p.message);
  await new Promise((r) => setTimeout(r, 200));
}
const steps = (await (await fetch(url + 'api/info')).json()).steps.length;
console.log(`whole series served (${steps} steps): ${since()} s`);
child.kill('SIGTERM');
await new Promise((resolve) => child.once('exit', resolve));
rmSync(dir, { recursive: true, force: true });
// Where the time went, from the server's log (-v): the first step's phases and the first still.
for (const line of out.split('\n').filter((l) => /spherical\S*: (read in|derived|levels)| still: /.test(l)).slice(0, 5))
  console.log('  ' + line.replace(/^\[[^\]]*\] \[\w+\] /, ''));
console.log(`load: ${readFileSync('/proc/loadavg', 'utf8').trim()}`);
