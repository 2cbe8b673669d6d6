// Benchmark (not a test): a still frame through the server alone and under mpirun (docs/scaling.md,
// the distributed server). For each run it starts `raypc serve DATASET --port 0` (with RANKS > 1
// under scripts/mpirun-local.sh -np RANKS), sends one still state over the WebSocket protocol and
// records every pass's `stats.passMs` (the pass's wall time on all ranks) and the time from sending
// the state to the converged frame. Runs alternate between the rank counts (interleaved A/B), so
// that a change in the machine's load hits both alike.
//
// node --experimental-websocket bench/server_ranks.mjs BUILD_DIR DATASET STATE.json [RUNS] [RANKS...]
//   e.g. node --experimental-websocket bench/server_ranks.mjs build /work/perf/full/dataset state.json 3 1 2
import { spawn } from 'node:child_process';
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const [build, dataset, statePath, runsText = '3', ...rankTexts] = process.argv.slice(2);
if (!build || !dataset || !statePath) {
  console.error('usage: node --experimental-websocket bench/server_ranks.mjs BUILD_DIR DATASET STATE.json [RUNS] [RANKS...]');
  process.exit(2);
}
if (typeof WebSocket !== 'function') {
  console.error('no WebSocket in this node: run it with --experimental-websocket (node 20) or node 22');
  process.exit(2);
}
const state = JSON.parse(readFileSync(statePath, 'utf8'));
const runs = Number(runsText);
const rankCounts = (rankTexts.length ? rankTexts : ['1', '2']).map(Number);

function startServer(ranks) {
  const serve = [join(build, 'raypc'), 'serve', dataset, '--port', '0'];
  const command = ranks > 1 ? [join(root, 'scripts', 'mpirun-local.sh'), '-np', String(ranks), ...serve] : serve;
  const child = spawn(command[0], command.slice(1), { stdio: ['ignore', 'pipe', 'pipe'] });
  return new Promise((resolve, reject) => {
    let out = '';
    const timer = setTimeout(() => reject(new Error(`no URL within 60 s: ${out}`)), 60000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = /raypc: serving (http:\/\/\S+)/.exec(out);
      if (m) { clearTimeout(timer); resolve({ child, url: m[1] }); }
    });
    child.stderr.on('data', (d) => { out += d; });
    child.once('exit', (code) => reject(new Error(`server exited with ${code}: ${out}`)));
  });
}

function stopServer(child) {
  return new Promise((resolve) => {
    const t = setTimeout(() => { child.kill('SIGKILL'); resolve(); }, 15000);
    child.once('exit', () => { clearTimeout(t); resolve(); });
    child.kill('SIGTERM');
  });
}

// One still state; resolves with every pass's header and the seconds to the converged frame.
function stillFrame(url) {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(url.replace(/^http/, 'ws').replace(/\/(\?|$)/, '/ws$1'));
    ws.binaryType = 'arraybuffer';
    const headers = [];
    let sent = 0;
    ws.onopen = () => {
      ws.send(JSON.stringify({ type: 'hello', protocol: 1 }));
      sent = performance.now();
      ws.send(JSON.stringify({ type: 'state', id: 1, state, interactive: false }));
    };
    ws.onmessage = (e) => {
      if (typeof e.data === 'string') {
        const m = JSON.parse(e.data);
        if (m.type === 'error') reject(new Error(m.message));
        return;
      }
      const bytes = new Uint8Array(e.data);
      const length = new DataView(e.data).getUint32(0, true);
      const h = JSON.parse(new TextDecoder().decode(bytes.subarray(4, 4 + length)));
      headers.push(h);
      if (h.converged) {
        const seconds = (performance.now() - sent) / 1000;
        ws.close();
        resolve({ headers, seconds });
      }
    };
    ws.onerror = (e) => reject(new Error(`WebSocket: ${e.message ?? e}`));
  });
}

const results = new Map(rankCounts.map((r) => [r, []]));
for (let run = 0; run < runs; ++run) {
  for (const ranks of rankCounts) {
    const { child, url } = await startServer(ranks);
    try {
      await stillFrame(url);  // warm: maps the step, computes its gradient, starts the threads
      const r = await stillFrame(url);
      const passMs = r.headers.map((h) => h.stats.passMs);
      results.get(ranks).push({ seconds: r.seconds, passMs, ranks: r.headers.at(-1).ranks });
      console.log(`run ${run + 1}, ${ranks} rank(s): converged in ${r.seconds.toFixed(2)} s; passes ${passMs.map((m) => m.toFixed(0)).join(' ')} ms; header ranks ${r.headers.at(-1).ranks}`);
    } finally {
      await stopServer(child);
    }
  }
}
const best = (xs) => Math.min(...xs);
console.log(`\nstate ${statePath}: ${state.image?.width}x${state.image?.height}, ${state.passes} passes; best of ${runs}`);
for (const ranks of rankCounts) {
  const rs = results.get(ranks);
  const meanPass = rs.map((r) => r.passMs.reduce((a, b) => a + b, 0) / r.passMs.length);
  console.log(`${ranks} rank(s): converged ${best(rs.map((r) => r.seconds)).toFixed(2)} s, mean pass ${best(meanPass).toFixed(0)} ms`);
}
console.log(`load: ${readFileSync('/proc/loadavg', 'utf8').trim()}`);
process.exit(0);
