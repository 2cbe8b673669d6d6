// Benchmark (not a test): how long a user waits for the browser UI's first picture of a 1° global
// seismic tomography model (tests/data/emc-layout/write_emc_layout.py --grid 25x181x361, its
// global_vs.nc, written once into a temporary directory unless --model names one). Each run starts
// `raypc serve global_vs.nc --dataset DIR --port 0` with DIR a fresh empty directory, and prints the
// seconds from the start of that process to:
//   1. "serving": the server's URL on stdout (the file preprocessed into DIR);
//   2. the page's DOMContentLoaded and load (the page opened as soon as the URL is printed);
//   3. the first frame of the 3D view on screen: the first entry of the UI's shownLog (a frame
//      decoded and handed to the view, which draws it at once), as tests/browser/measure.mjs's first
//      picture; the first state sent and the first frame received are printed beside it;
//   4. the converged frame on screen: the first shown frame that is converged and answers the newest
//      state sent (tests/browser/harness.mjs's waitConverged).
// The page's times come from its own clock (performance.timeOrigin) put on this process's.
// The UI is the one with the test hooks (web/dist-test, scripts/build-web.sh), opened as
// harness.mjs opens it: Debian's chromium headless through playwright-core with the same switches
// (--disable-gpu, SwiftShader), a fresh profile per run. The browser is started before the clock,
// as a user's browser is already open. The machine's load (os.loadavg: 1, 5, 15 minutes, renewed
// every 5 s, so a short run's two often read alike) is printed at the start and the end of each
// run; after RUNS runs (default 3), the min and median of each time. The server,
// the browser and the temporary directories are removed at the end, also on failure or Ctrl-C.
//   node bench/ui_first_picture.mjs RAYPC [RUNS] [--viewport WxH] [--assets DIR] [--model FILE.nc]
// --viewport: the browser window (default 1920x1080, where the 3D view is 1500x627 as in docs/ui.md).
import { spawn, spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, rmSync } from 'node:fs';
import { createRequire } from 'node:module';
import { loadavg, tmpdir } from 'node:os';
import { join } from 'node:path';
import { chromiumArgs, chromiumPath, repoRoot } from '../tests/browser/harness.mjs';

const args = process.argv.slice(2);
const flag = (name, fallback) => { const i = args.indexOf(name); return i < 0 ? fallback : args.splice(i, 2)[1]; };
const viewportText = flag('--viewport', '1920x1080');
const assets = flag('--assets', join(repoRoot, 'web', 'dist-test'));
let model = flag('--model', null);
const [raypc, runsText = '3'] = args;
const runs = Number(runsText);
if (!raypc || !existsSync(raypc) || !Number.isInteger(runs) || runs < 1 || !/^\d+x\d+$/.test(viewportText)) {
  console.error('usage: node bench/ui_first_picture.mjs RAYPC [RUNS] [--viewport WxH] [--assets DIR] [--model FILE.nc]');
  process.exit(2);
}
const [vw, vh] = viewportText.split('x').map(Number);
for (const [what, path] of [['chromium', chromiumPath], ['the UI with its test hooks (scripts/build-web.sh)', join(assets, 'index.html')]]) {
  if (!existsSync(path)) {
    console.error(`${what} not found: ${path}`);
    process.exit(1);
  }
}
const { chromium } = createRequire(join(repoRoot, 'web', 'package.json'))('playwright-core');
const runLimitMs = 120000;

// Everything to remove at the end; cleanup() runs on success, failure and SIGINT/SIGTERM.
// One clean-up at a time (a signal's and the failing run's): the directories go only once the
// browser has closed, which writes into its profile until then.
const live = { server: null, context: null, dirs: [] };
let cleaning = null;
function cleanup() {
  cleaning ??= (async () => {
    while (live.server || live.context || live.dirs.length) {
      const { server, context } = live;
      live.server = live.context = null;
      if (context) await Promise.resolve(context).then((c) => c.close()).catch(() => {}); // launched or still launching
      if (server && server.exitCode === null && server.signalCode === null) {
        server.kill('SIGTERM');
        await new Promise((r) => {
          const t = setTimeout(() => { server.kill('SIGKILL'); r(); }, 3000);
          server.once('exit', () => { clearTimeout(t); r(); });
        });
      }
      for (const d of live.dirs.splice(0)) {
        try {
          rmSync(d, { recursive: true, force: true, maxRetries: 5 });
        } catch (e) {
          console.error(`could not remove ${d}: ${e.message}`);
        }
      }
    }
  })().finally(() => { cleaning = null; });
  return cleaning;
}
for (const sig of ['SIGINT', 'SIGTERM']) {
  process.once(sig, async () => {
    console.error(`\n${sig}: cleaning up`);
    await cleanup();
    process.exit(130);
  });
}

const load = () => loadavg().map((x) => x.toFixed(2)).join(' ');
const epochNow = () => performance.timeOrigin + performance.now();
const median = (a) => { const s = [...a].sort((x, y) => x - y); return s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2; };

function waitForUrl(proc, out) {
  return new Promise((resolve, reject) => {
    proc.stdout.on('data', (d) => {
      out.text += d;
      const m = /serving (http:\/\/127\.0\.0\.1:\d+\/)/.exec(out.text);
      if (m) resolve({ url: m[1], t: epochNow() });
    });
    proc.once('exit', (code) => reject(new Error(`raypc serve exited with ${code} before printing its URL:\n${out.text}`)));
  });
}

async function oneRun(run) {
  const tmp = mkdtempSync(join(tmpdir(), 'raypc-uibench-'));
  live.dirs.push(tmp);
  const dataset = join(tmp, 'ds');
  const tLaunch = epochNow();
  live.context = chromium.launchPersistentContext(join(tmp, 'profile'), {
    executablePath: chromiumPath, headless: true, viewport: { width: vw, height: vh }, args: chromiumArgs(false),
    handleSIGINT: false, handleSIGTERM: false, // cleanup() closes it
  });
  const context = await live.context;
  await context.addInitScript(() => { window.__raypcTestHooks = true; }); // web/src/test_hooks.ts
  const page = context.pages()[0] ?? await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });

  const loadStart = load();
  const t0 = epochNow();
  const s = (epochMs) => (epochMs - t0) / 1000;
  const out = { text: '' };
  live.server = spawn(raypc, ['-v', 'serve', model, '--dataset', dataset, '--port', '0', '--assets', assets,
    '--examples', join(repoRoot, 'examples')], { stdio: ['ignore', 'pipe', 'pipe'] });
  live.server.stderr.on('data', (d) => { out.text += d; });
  const { url, t: tServing } = await waitForUrl(live.server, out);
  await page.goto(url, { waitUntil: 'load', timeout: runLimitMs });
  // The newest state sent answered by a converged frame (harness.mjs's waitConverged), and that very
  // frame on screen (lastShownId alone is already the state's id once its first pass is shown).
  await page.waitForFunction(() => {
    const r = window.__raypc;
    const h = r?.headers[r.headers.length - 1];
    return h && h.converged && h.id === r.lastSentId && r.lastShownId === h.id && r.shownLog.some((e) => e.id === h.id && e.pass === h.pass);
  }, null, { timeout: runLimitMs, polling: 50 }).catch(async (e) => {
    throw new Error(`no converged frame on screen within ${runLimitMs / 1000} s (${e.message}); page errors: ${errors.join(' | ')}`);
  });
  const p = await page.evaluate(() => {
    const r = window.__raypc, nav = performance.getEntriesByType('navigation')[0];
    const h = r.headers[r.headers.length - 1];
    const shown = r.shownLog.find((e) => e.id === h.id && e.pass === h.pass);
    return { origin: performance.timeOrigin, dcl: nav.domContentLoadedEventEnd, load: nav.loadEventEnd,
      sent: r.sentLog[0]?.t, received: r.frameLog[0]?.t, first: r.shownLog[0], converged: shown.t, pass: h.pass, image: r.state().image };
  });
  const at = (ms) => s(p.origin + ms);
  const f = p.first;
  const times = {
    serving: s(tServing),
    domContentLoaded: at(p.dcl),
    load: at(p.load),
    firstFrame: at(f.t),
    converged: at(p.converged),
  };
  console.log(`run ${run}: load at start ${loadStart} (chromium started before, in ${((t0 - tLaunch) / 1000).toFixed(2)} s)`);
  console.log(`  serving (URL on stdout):       ${times.serving.toFixed(2)} s`);
  console.log(`  page DOMContentLoaded:         ${times.domContentLoaded.toFixed(2)} s`);
  console.log(`  page load:                     ${times.load.toFixed(2)} s`);
  console.log(`  first state sent:              ${p.sent === undefined ? '?' : at(p.sent).toFixed(2)} s`);
  console.log(`  first frame received:          ${p.received === undefined ? '?' : at(p.received).toFixed(2)} s`);
  console.log(`  first frame on screen:         ${times.firstFrame.toFixed(2)} s (level ${f.level}, ${f.width}x${f.height}, pass ${f.pass})`);
  console.log(`  converged frame on screen:     ${times.converged.toFixed(2)} s (pass ${p.pass}; state ${p.image.width}x${p.image.height})`);
  // Where the server's time went before "serving" (its -v log).
  const stamp = (line) => { const m = /^\[[^\]]* (\d\d):(\d\d):(\d\d\.\d+)\]/.exec(line); return m ? (+m[1] * 3600 + +m[2] * 60 + +m[3]) : null; };
  const d0 = new Date(t0), start = d0.getHours() * 3600 + d0.getMinutes() * 60 + d0.getSeconds() + d0.getMilliseconds() / 1000;
  for (const l of out.text.split('\n').filter((x) => /the dataset of|read in|levels, bricks|serving the UI| still: /.test(x))) {
    const t = stamp(l);
    if (t !== null) console.log(`    server log ${(t - start).toFixed(2)} s: ${l.replace(/^\[[^\]]*\] \[\w+\] /, '')}`);
  }
  await cleanup();
  console.log(`  load at end ${load()}`);
  if (errors.length) console.log(`  page errors: ${errors.join(' | ')}`);
  return times;
}

let failed = false;
try {
  if (!model) {
    const dir = mkdtempSync(join(tmpdir(), 'raypc-uibench-model-'));
    live.dirs.push(dir);
    const w = spawnSync('/usr/bin/python3', [join(repoRoot, 'tests/data/emc-layout/write_emc_layout.py'), dir, '--grid', '25x181x361'],
      { encoding: 'utf8' });
    if (w.status !== 0) throw new Error(`write_emc_layout.py failed (${w.status}): ${w.stderr}`);
    model = join(dir, 'global_vs.nc');
  }
  const modelDirs = live.dirs.splice(0); // kept across the runs
  const all = [];
  try {
    for (let i = 1; i <= runs; i++) all.push(await oneRun(i));
  } finally {
    live.dirs.push(...modelDirs);
  }
  console.log(`${runs} runs, window ${viewportText}, ${model.includes('raypc-uibench-model-') ? 'global_vs.nc 25x181x361' : model}; seconds from the start of raypc serve:`);
  console.log('                          min   median');
  for (const k of Object.keys(all[0])) {
    const v = all.map((t) => t[k]);
    console.log(`  ${k.padEnd(20)} ${Math.min(...v).toFixed(2).padStart(6)} ${median(v).toFixed(2).padStart(8)}`);
  }
} catch (e) {
  console.error(`ui_first_picture: ${e.stack ?? e}`);
  failed = true;
} finally {
  await cleanup();
}
process.exit(failed ? 1 : 0);
