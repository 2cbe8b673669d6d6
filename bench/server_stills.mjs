// Benchmark (not a test): where the time of a still frame goes in the server, from its own log.
// Starts `raypc -v serve DATASET --port 0`, sends STATE.json (its `level` dropped, 2 passes) as a
// still, then alternately an interactive and a still state with a temperature brush whose maximum
// moves (as a user releasing a brush does), and prints the server's log line of every still:
// "prepared", the first pass, the mean pass, and "encode" (picture, depth map and JPEG per frame).
//   node --experimental-websocket bench/server_stills.mjs BUILD_DIR DATASET STATE.json
import { spawn } from 'node:child_process';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';

const [build, dataset, statePath] = process.argv.slice(2);
if (!build || !dataset || !statePath || typeof WebSocket !== 'function') {
  console.error('usage: node --experimental-websocket bench/server_stills.mjs BUILD_DIR DATASET STATE.json');
  process.exit(2);
}
const base = JSON.parse(readFileSync(statePath, 'utf8'));
delete base.level;
base.passes = 2;
const child = spawn(join(build, 'raypc'), ['-v', 'serve', dataset, '--port', '0'], { stdio: ['ignore', 'pipe', 'inherit'] });
let log = '';
const url = await new Promise((resolve) => child.stdout.on('data', (d) => {
  log += d;
  const m = /serving (http:\/\/\S+)/.exec(log);
  if (m) resolve(m[1]);
}));
const ws = new WebSocket(url.replace(/^http/, 'ws') + 'ws');
ws.binaryType = 'arraybuffer';
await new Promise((resolve) => { ws.onopen = resolve; });
ws.send(JSON.stringify({ type: 'hello', protocol: 1 }));
const converged = (id) => new Promise((resolve) => {
  ws.onmessage = (e) => {
    if (typeof e.data === 'string') return;
    const n = new DataView(e.data).getUint32(0, true);
    const h = JSON.parse(new TextDecoder().decode(new Uint8Array(e.data, 4, n)));
    if (h.id === id && h.converged) resolve(h);
  };
});
let id = 0;
for (const [max, interactive] of [[2500, false], [2400, true], [2400, false], [2300, true], [2300, false]]) {
  ws.send(JSON.stringify({ type: 'state', id: ++id, state: { ...base, brushes: [{ name: 'temperature', min: 1500, max }] }, interactive }));
  await converged(id);
}
ws.close();
child.kill('SIGTERM');
await new Promise((resolve) => child.once('exit', resolve));
for (const line of log.split('\n').filter((l) => / still: /.test(l))) console.log(line.replace(/^.*?session/, 'session'));
console.log(`load: ${readFileSync('/proc/loadavg', 'utf8').trim()}`);
process.exit(0);
