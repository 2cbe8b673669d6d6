// The frame rate of two datasets side by side (docs/compare.md, "Side by side"; not part of ctest:
// speed is reported, not asserted):
//   node tests/browser/measure_compare.mjs RAYPC DATASET_A DATASET_B [--seconds 8] [--viewport 1920x1080] [--gpu]
// 1. `raypc serve A B`: the camera orbited on the first view for S seconds (a pointer move every
//    display frame, as measure.mjs --orbit drives it): frames shown per second in each view, their
//    sizes and levels.
// 2. `raypc serve A` with the 3D view's panel as wide as one view of the pair was: the same orbit,
//    frames shown per second — what each view of the pair is compared with.
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { chromiumArgs, chromiumPath, repoRoot, waitConverged } from './harness.mjs';

const args = process.argv.slice(2);
const flag = (name) => { const i = args.indexOf(name); return i < 0 ? null : args.splice(i, name === '--gpu' ? 1 : 2).at(-1); };
const seconds = Number(flag('--seconds') ?? 8);
const viewport = (flag('--viewport') ?? '1920x1080').split('x').map(Number);
const gpu = flag('--gpu') !== null;
const [raypc, a, b] = args;
const { chromium } = createRequire(join(repoRoot, 'web', 'package.json'))('playwright-core');
const assets = join(repoRoot, 'web', 'dist-test');

async function withUi(datasets, body) {
  const server = spawn(raypc, ['serve', ...datasets, '--port', '0', '--assets', assets], { stdio: ['ignore', 'pipe', 'inherit'] });
  const url = await new Promise((resolve, reject) => {
    let out = '';
    server.stdout.on('data', (d) => { out += d; const m = /(http:\/\/127\.0\.0\.1:\d+\/)/.exec(out); if (m) resolve(m[1]); });
    server.on('exit', (c) => reject(new Error(`raypc serve exited with ${c}`)));
  });
  const profile = mkdtempSync(join(tmpdir(), 'raypc-measure-compare-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: chromiumPath, headless: true, viewport: { width: viewport[0], height: viewport[1] }, args: chromiumArgs(gpu),
  });
  try {
    await context.addInitScript(() => { window.__raypcTestHooks = true; });
    const page = await context.newPage();
    await page.goto(url);
    await page.waitForFunction(() => window.__raypc && window.__raypc.headers.length > 0 && window.__raypc.parcoords.timing.drawnAt.foreground > 0,
      null, { timeout: 60000 });
    await waitConverged(page, 60000);
    return await body(page);
  } finally {
    await context.close();
    server.kill('SIGTERM');
    rmSync(profile, { recursive: true, force: true });
  }
}

// Orbits for `seconds` on the first view; frames shown per second in it and (a pair) in the second.
async function orbit(page) {
  const box = await page.evaluate(() => { const r = document.getElementById('view3d').getBoundingClientRect(); return { x: r.x + r.width / 2, y: r.y + r.height / 2 }; });
  await page.mouse.move(box.x, box.y);
  const since = await page.evaluate(() => ({ shown: window.__raypc.shownLog.length, second: window.__raypc.pair?.headers.length ?? 0, t: performance.now() }));
  await page.mouse.down();
  await page.evaluate(([x0, y0, ms]) => new Promise((resolve) => {
    const target = document.elementFromPoint(x0, y0);
    const start = performance.now();
    let i = 0;
    const step = () => {
      if (performance.now() - start >= ms) return resolve(i);
      target.dispatchEvent(new PointerEvent('pointermove', { pointerId: 1, pointerType: 'mouse', isPrimary: true, buttons: 1,
        clientX: x0 + 200 * Math.sin(i / 40), clientY: y0 + 40 * Math.sin(i / 70), bubbles: true }));
      i++;
      requestAnimationFrame(step);
    };
    requestAnimationFrame(step);
  }), [box.x, box.y, seconds * 1000]);
  const r = await page.evaluate((n) => {
    const shown = window.__raypc.shownLog.slice(n.shown).filter((f) => f.t >= n.t);
    const p = window.__raypc.pair;
    return { shown: shown.map((s) => `${s.width}x${s.height}@${s.level}`), second: p ? p.headers.slice(-(p.headers.length - n.second)).map((h) => `${h.width}x${h.height}@${h.level}`) : null,
      secondCount: p ? p.headers.length - n.second : 0, elapsed: (performance.now() - n.t) / 1000 };
  }, since);
  await page.mouse.up();
  const count = (list) => { const c = {}; for (const s of list) c[s] = (c[s] ?? 0) + 1; return JSON.stringify(c); };
  const out = { first: r.shown.length / r.elapsed, firstSizes: count(r.shown) };
  if (r.second) Object.assign(out, { second: r.secondCount / r.elapsed, secondSizes: count(r.second) });
  return out;
}

const pair = await withUi([a, b], async (page) => {
  await page.waitForFunction(() => window.__raypc.pair?.headers.some((h) => h.converged), null, { timeout: 60000 });
  const width = await page.evaluate(() => document.getElementById('view3d').getBoundingClientRect().width);
  return { width, ...(await orbit(page)) };
});
console.log(`pair (viewport ${viewport.join('x')}, each view ${pair.width.toFixed(0)} px wide), orbit ${seconds} s: ` +
  `A ${pair.first.toFixed(1)} frames/s shown ${pair.firstSizes}; B ${pair.second.toFixed(1)} frames/s ${pair.secondSizes} (size@level)`);
const one = await withUi([a], async (page) => {
  await page.addStyleTag({ content: `#viewPanel { width: ${pair.width}px; }` });
  await page.evaluate(() => new Promise((r) => setTimeout(r, 500)));
  await waitConverged(page, 60000);
  const width = await page.evaluate(() => document.getElementById('view3d').getBoundingClientRect().width);
  return { width, ...(await orbit(page)) };
});
console.log(`one view ${one.width.toFixed(0)} px wide (half the pair's panel), orbit ${seconds} s: ${one.first.toFixed(1)} frames/s shown ${one.firstSizes}`);
