// Shared set-up of the browser tests: preprocess the fixture, start `raypc serve` on a free port,
// launch Debian's chromium through playwright-core with a fresh profile, and tear everything down.
// Only 127.0.0.1 is contacted. Every failure names what was missing or what went wrong.
import { spawn, spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readdirSync, rmSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

export const repoRoot = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
export const chromiumPath = process.env.RAYPC_CHROMIUM ?? '/usr/bin/chromium';

// A binary message of the server (a frame, pathlines, a map or section: docs/protocol.md): a u32
// length, the JSON header, then the body. `bytes` an ArrayBuffer or a Buffer.
export function binaryHeader(bytes) {
  const buffer = Buffer.isBuffer(bytes) ? bytes : Buffer.from(bytes);
  const n = buffer.readUInt32LE(0);
  return { header: JSON.parse(buffer.subarray(4, 4 + n).toString('utf8')), bodyOffset: 4 + n };
}

// Chromium's switches for the tests and measure.mjs: software compositing (--disable-gpu), or with
// `gpu` GPU compositing, both on SwiftShader; nothing contacted but 127.0.0.1.
export function chromiumArgs(gpu) {
  return ['--no-sandbox', ...(gpu ? ['--enable-gpu-rasterization', '--ignore-gpu-blocklist'] : ['--disable-gpu']), '--use-angle=swiftshader',
    '--enable-unsafe-swiftshader', '--disable-quic', '--no-first-run', '--disable-background-networking', '--disable-component-update',
    '--disable-sync', '--disable-features=Translate,MediaRouter,OptimizationHints', '--disable-dev-shm-usage'];
}

export class TestFailure extends Error {}

export function check(condition, message) {
  if (!condition) throw new TestFailure(message);
}

function loadPlaywright() {
  const require = createRequire(join(repoRoot, 'web', 'package.json'));
  try {
    return require('playwright-core');
  } catch {
    throw new TestFailure(`playwright-core is not installed in ${join(repoRoot, 'web', 'node_modules')}: run scripts/build-web.sh`);
  }
}

function waitForUrl(proc, timeoutMs) {
  return new Promise((resolvePromise, reject) => {
    let out = '', err = '';
    const timer = setTimeout(() => reject(new TestFailure(`raypc serve printed no URL within ${timeoutMs} ms; stdout: ${out} stderr: ${err}`)), timeoutMs);
    proc.stdout.on('data', (d) => {
      out += d;
      const m = /(http:\/\/127\.0\.0\.1:(\d+)\/)/.exec(out);
      if (m) {
        clearTimeout(timer);
        resolvePromise(m[1]);
      }
    });
    proc.stderr.on('data', (d) => { err += d; if (err.length > 20000) err = err.slice(-10000); });
    proc.on('exit', (code) => {
      clearTimeout(timer);
      reject(new TestFailure(`raypc serve exited with ${code} before printing its URL; stderr: ${err}`));
    });
  });
}

// Runs `body({ browser, context, url, dataset, tmp })` and always cleans up. Exits the process
// with 0 on success, 1 on failure, and never runs past `limitMs`.
// `contextOptions` go to chromium's context (e.g. a viewport or deviceScaleFactor); `gpu` runs
// chromium with GPU rasterisation on a software GL (SwiftShader), as on a machine without a GPU,
// instead of --disable-gpu.
// `ranks` > 1 starts the server under MPI (scripts/mpirun-local.sh -np RANKS: a distributed server).
// `netcdf`: serve the fixture's netCDF files themselves (raypc serve FILE.nc…), the background run of
// the series held until the case creates `${tmp}/go` (RAYPC_TEST_HOLD_SERIES).
// `pairSeeds` [A, B]: instead of the fixture, two synthetic runs (`raypc synth --seed`) of these seeds,
// preprocessed into `${tmp}/seedA` and `${tmp}/seedB` and served as a pair (`raypc serve A B`).
export async function runCase(name, raypc, fixture, body, { limitMs = 100000, contextOptions = {}, gpu = false, sampleRows = 5000, ranks = 1, netcdf = false, pairSeeds = null } = {}) {
  const started = Date.now();
  let server = null, context = null, tmp = null;
  const cleanup = async () => {
    if (context) await context.close().catch(() => {});
    context = null;
    if (server && server.exitCode === null) {
      server.kill('SIGTERM');
      await new Promise((r) => { const t = setTimeout(() => { server.kill('SIGKILL'); r(); }, 3000); server.once('exit', () => { clearTimeout(t); r(); }); });
    }
    if (tmp) rmSync(tmp, { recursive: true, force: true });
    tmp = null;
  };
  const watchdog = setTimeout(async () => {
    console.error(`FAIL ${name}: took longer than ${limitMs} ms`);
    await cleanup();
    process.exit(1);
  }, limitMs);
  try {
    check(existsSync(chromiumPath), `chromium is not installed at ${chromiumPath} (Debian package 'chromium'; scripts/install-deps.sh installs it)`);
    check(raypc && existsSync(raypc), `raypc binary not found: ${raypc}`);
    check(fixture && existsSync(fixture), `fixture not found: ${fixture}`);
    const dist = join(repoRoot, 'web', 'dist-test'); // the UI with its test hooks (web/build.mjs)
    check(existsSync(join(dist, 'index.html')), `the UI is not built (${dist}/index.html missing): run scripts/build-web.sh`);
    const { chromium } = loadPlaywright();

    tmp = mkdtempSync(join(tmpdir(), `raypc-browser-${name}-`));
    const dataset = join(tmp, 'ds');
    let inputs = [dataset];
    if (pairSeeds) {
      inputs = pairSeeds.map((seed) => join(tmp, `seed${seed}`));
      for (const [i, seed] of pairSeeds.entries()) {
        const files = join(tmp, `synth${seed}`);
        const synth = spawnSync(raypc, ['synth', '-o', files, '--seed', String(seed), '--steps', '3', '--grid', '32x41x64'], { encoding: 'utf8', timeout: 60000 });
        check(synth.status === 0, `raypc synth --seed ${seed} failed (${synth.status}): ${synth.stderr}`);
        const pre = spawnSync(raypc, ['preprocess', files, '-o', inputs[i], '--quiet', '--sample-rows', String(sampleRows)], { encoding: 'utf8', timeout: 60000 });
        check(pre.status === 0, `raypc preprocess of seed ${seed} failed (${pre.status}): ${pre.stderr}`);
      }
    } else if (netcdf) {
      inputs = readdirSync(fixture).filter((f) => f.endsWith('.nc')).sort().map((f) => join(fixture, f));
      inputs.push('--dataset', dataset, '--sample-rows', String(sampleRows));
    } else {
      const pre = spawnSync(raypc, ['preprocess', fixture, '-o', dataset, '--quiet', '--sample-rows', String(sampleRows)], { encoding: 'utf8', timeout: 60000 });
      check(pre.status === 0, `raypc preprocess failed (${pre.status}): ${pre.stderr}`);
    }

    const serve = [raypc, 'serve', ...inputs, '--port', '0', '--assets', dist, '--examples', join(repoRoot, 'examples')];
    const command = ranks > 1 ? [join(repoRoot, 'scripts', 'mpirun-local.sh'), '-np', String(ranks), ...serve] : serve;
    const env = netcdf ? { ...process.env, RAYPC_TEST_HOLD_SERIES: join(tmp, 'go') } : process.env;
    server = spawn(command[0], command.slice(1), { stdio: ['ignore', 'pipe', 'pipe'], env });
    const url = await waitForUrl(server, 20000);

    context = await chromium.launchPersistentContext(join(tmp, 'profile'), {
      executablePath: chromiumPath,
      headless: true,
      acceptDownloads: true,
      viewport: { width: 1280, height: 860 },
      ...contextOptions,
      args: chromiumArgs(gpu),
    });
    // The UI installs window.__raypc (web/src/test_hooks.ts) only when asked before it loads; the
    // tests' own page helper __viewImageData reads the 3D view at full resolution (ImageData).
    await context.addInitScript(() => {
      window.__raypcTestHooks = true;
      window.__viewImageData = () => {
        const src = document.getElementById('view3d');
        const c = document.createElement('canvas');
        c.width = src.width; c.height = src.height;
        const ctx = c.getContext('2d', { willReadFrequently: true });
        ctx.drawImage(src, 0, 0);
        return ctx.getImageData(0, 0, c.width, c.height);
      };
    });
    await body({ context, url, dataset, tmp, raypc, gpu });
    console.log(`PASS ${name} (${((Date.now() - started) / 1000).toFixed(1)} s)`);
    clearTimeout(watchdog);
    await cleanup();
    process.exit(0);
  } catch (e) {
    console.error(`FAIL ${name}: ${e instanceof TestFailure ? e.message : e.stack ?? e}`);
    clearTimeout(watchdog);
    await cleanup();
    process.exit(1);
  }
}

// Opens the UI (optionally with a state in the URL) and waits until it shows a converged frame.
export async function openUi(context, url, { hash = '', timeoutMs = 30000 } = {}) {
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  const warnings = [];
  page.on('console', (m) => {
    if (m.type() === 'error') errors.push(m.text());
    else if (m.type() === 'warning') warnings.push(m.text());
  });
  page.raypcErrors = errors;
  page.raypcWarnings = warnings;
  await page.goto(url + hash);
  await page.waitForFunction(() => window.__raypc && window.__raypc.headers.length > 0, null, { timeout: timeoutMs })
    .catch(() => { throw new TestFailure(`no frame arrived within ${timeoutMs} ms; page errors: ${errors.join(' | ')}`); });
  await waitConverged(page, timeoutMs);
  return page;
}

// The volume alone, for the re-projection checks (warp, stereo): without the core, whose shading
// follows the camera (light in the camera frame), and the reference shells, whose depth labels are
// written in screen space; no re-projection of an image can reproduce either.
export async function volumeOnly(page) {
  await page.evaluate(() => {
    const s = window.__raypc.state();
    window.__raypc.setState({ ...s, core: { ...s.core, visible: false },
      reference: { ...s.reference, shells: { ...s.reference.shells, visible: false } } });
  });
}

// A square image with the planet filling most of it, so image differences are not diluted.
export async function standardView(page) {
  await page.evaluate(() => {
    const s = window.__raypc.state();
    window.__raypc.setState({ ...s, image: { width: 384, height: 384 }, camera: { ...s.camera, distanceKm: 16000 } });
  });
  await waitConverged(page);
}

// Waits until the newest sent state has been answered by a converged frame that is on screen.
export async function waitConverged(page, timeoutMs = 30000) {
  // After page.goto the UI's hooks appear only once its script has started: until then, wait.
  await page.waitForFunction(() => {
    const r = window.__raypc;
    const h = r?.headers[r.headers.length - 1];
    return h && h.converged && h.id === r.lastSentId && r.lastShownId === h.id;
  }, null, { timeout: timeoutMs, polling: 50 }).catch(async () => {
    const info = await page.evaluate(() => { const r = window.__raypc; return r ? { lastSent: r.lastSentId, shown: r.lastShownId, last: r.headers[r.headers.length - 1], errors: r.errors } : 'the UI did not start'; });
    throw new TestFailure(`no converged frame for the newest state within ${timeoutMs} ms: ${JSON.stringify(info)}`);
  });
  // One more display frame so the canvas holds it.
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
}

// The 3D view's image (its letterboxed viewport), box-filtered to n x n grey levels (0..255).
export async function viewPixels(page, n = 64) {
  return page.evaluate((n) => {
    // Only the image's letterboxed viewport, as View3D.draw places it.
    const src = document.getElementById('view3d');
    const { width, height } = window.__raypc.state().image;
    const cw = src.width, ch = src.height, aspect = width / height;
    let vw = cw, vh = Math.round(cw / aspect);
    if (vh > ch) { vh = ch; vw = Math.round(ch * aspect); }
    // Box-filter the viewport down to n x n grey levels (drawImage's own scaling samples too few pixels).
    const c = document.createElement('canvas');
    c.width = vw; c.height = vh;
    const ctx = c.getContext('2d', { willReadFrequently: true });
    ctx.drawImage(src, Math.floor((cw - vw) / 2), Math.ceil((ch - vh) / 2), vw, vh, 0, 0, vw, vh);
    const d = ctx.getImageData(0, 0, vw, vh).data;
    const sum = new Float64Array(n * n), count = new Float64Array(n * n);
    for (let y = 0; y < vh; y++) {
      const by = Math.min(n - 1, Math.floor((y * n) / vh));
      for (let x = 0; x < vw; x++) {
        const k = by * n + Math.min(n - 1, Math.floor((x * n) / vw)), o = (y * vw + x) * 4;
        sum[k] += (d[o] + d[o + 1] + d[o + 2]) / 3;
        count[k]++;
      }
    }
    return Array.from(sum, (v, k) => v / Math.max(1, count[k]));
  }, n);
}

export function meanAbsDiff(a, b) {
  let s = 0;
  for (let i = 0; i < a.length; i++) s += Math.abs(a[i] - b[i]);
  return s / a.length;
}

export async function postJson(url, body) {
  const r = await fetch(url, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
  const text = await r.text();
  return { status: r.status, body: r.headers.get('content-type')?.includes('json') ? JSON.parse(text) : text };
}
