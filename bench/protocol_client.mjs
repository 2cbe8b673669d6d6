// What the protocol benchmarks share (bench/playback_loops.mjs, bench/step_change.mjs): `raypc serve`
// on a dataset at a free port, its /api/info, and a WebSocket session after hello (docs/protocol.md).
import { spawn } from 'node:child_process';

// Starts `raypc [-v] serve DATASET --port 0 EXTRA...`; resolves when it serves, with the child, the
// base URL and /api/info. `verbose` passes -v and copies the server's output to stderr. A server that
// exits before serving rejects with its exit code.
export async function startServer(raypc, dataset, extra = [], { verbose = false } = {}) {
  const child = spawn(raypc, [...(verbose ? ['-v'] : []), 'serve', dataset, '--port', '0', ...extra],
    { stdio: ['ignore', 'pipe', 'inherit'] });
  let out = '';
  const url = await new Promise((resolve, reject) => {
    child.once('exit', (code) => reject(new Error(`raypc serve exited (${code}) before serving`)));
    child.stdout.on('data', (d) => {
      if (verbose) process.stderr.write(d);
      out += d;
      const m = /serving (http:\/\/\S+)/.exec(out);
      if (m) resolve(m[1]);
    });
  });
  const info = await (await fetch(url + 'api/info')).json();
  return { child, url, info };
}

// A session of the server at `url`, after the hello of protocol 1; binary messages as ArrayBuffers.
export async function openSession(url) {
  const ws = new WebSocket(url.replace(/^http/, 'ws') + 'ws');
  ws.binaryType = 'arraybuffer';
  await new Promise((resolve) => { ws.onopen = resolve; });
  ws.send(JSON.stringify({ type: 'hello', protocol: 1 }));
  return ws;
}
