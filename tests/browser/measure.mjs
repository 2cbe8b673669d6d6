// Measurements of the UI on a real dataset (not part of ctest; speed is reported, not asserted):
//   node tests/browser/measure.mjs RAYPC DATASET [SCREENSHOT.png]
// 1. brush-to-updated-frame latency at 512x512: a brush on the temperature axis is dragged with
//    the mouse; for every state the brush sent, the time from sending it to its first frame on
//    screen (decoded and drawn), separately for interactive states (while dragging) and the final
//    state (on release).
// 2. parallel-coordinates responsiveness with the dataset's sample (100 000 lines by default):
//    for each mouse move of a brush, the time from the input event to the next animation frame
//    (parcoord-es filters every line and starts redrawing inside that frame), and the longest task.
// 3. optionally a screenshot of the whole UI.
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import { join } from 'node:path';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { chromiumPath, repoRoot, waitConverged } from './harness.mjs';

const [raypc, dataset, screenshot] = process.argv.slice(2);
const { chromium } = createRequire(join(repoRoot, 'web', 'package.json'))('playwright-core');
const median = (a) => { const s = [...a].sort((x, y) => x - y); return s.length ? s[Math.floor(s.length / 2)] : NaN; };
const pct = (a, p) => { const s = [...a].sort((x, y) => x - y); return s[Math.min(s.length - 1, Math.floor(s.length * p))]; };

const server = spawn(raypc, ['serve', dataset, '--port', '0', '--assets', join(repoRoot, 'web', 'dist')], { stdio: ['ignore', 'pipe', 'inherit'] });
const url = await new Promise((resolve, reject) => {
  let out = '';
  server.stdout.on('data', (d) => { out += d; const m = /(http:\/\/127\.0\.0\.1:\d+\/)/.exec(out); if (m) resolve(m[1]); });
  server.on('exit', (c) => reject(new Error(`raypc serve exited with ${c}`)));
});
const profile = mkdtempSync(join(tmpdir(), 'raypc-measure-'));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: chromiumPath, headless: true, viewport: { width: 1280, height: 860 },
  args: ['--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync'],
});
try {
  await context.addInitScript(() => { window.__raypcTestHooks = true; }); // web/src/test_hooks.ts
  const page = await context.newPage();
  await page.goto(url);
  await page.waitForFunction(() => window.__raypc && window.__raypc.parcoords.rowCount > 0 && window.__raypc.headers.length > 0, null, { timeout: 60000 });
  await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, image: { width: 512, height: 512 } }); });
  await waitConverged(page, 60000);
  const rows = await page.evaluate(() => window.__raypc.parcoords.rowCount);

  // Input-to-next-frame timing of every mouse move.
  await page.evaluate(() => {
    window.__moves = [];
    window.__longest = 0;
    new PerformanceObserver((l) => { for (const e of l.getEntries()) window.__longest = Math.max(window.__longest, e.duration); }).observe({ type: 'longtask', buffered: false });
    window.addEventListener('mousemove', (e) => {
      if (!window.__measuring) return;
      const t0 = e.timeStamp;
      requestAnimationFrame(() => window.__moves.push(performance.now() - t0));
    }, true);
  });
  const box = await page.evaluate(() => {
    for (const g of document.querySelectorAll('#parcoords svg g.dimension'))
      if (g.__data__ === 'temperature') { const r = g.querySelector('.brush .overlay').getBoundingClientRect(); return { x: r.x, y: r.y, w: r.width, h: r.height }; }
    return null;
  });
  const x = box.x + box.w / 2;
  const since = await page.evaluate(() => window.__raypc.latencies.length);
  const drags = 8;
  for (let k = 0; k < drags; k++) {
    const y0 = box.y + box.h * (0.1 + 0.04 * k), y1 = y0 + box.h * 0.3;
    await page.mouse.move(x, y0);
    await page.mouse.down();
    await page.evaluate(() => { window.__measuring = true; });
    for (let i = 1; i <= 10; i++) { await page.mouse.move(x, y0 + ((y1 - y0) * i) / 10); await page.waitForTimeout(30); }
    await page.evaluate(() => { window.__measuring = false; });
    await page.mouse.up();
    await waitConverged(page, 60000);
  }
  const r = await page.evaluate((n) => ({ lat: window.__raypc.latencies.slice(n), moves: window.__moves, longest: window.__longest, last: window.__raypc.headers.at(-1) }), since);
  const inter = r.lat.filter((l) => l.interactive).map((l) => l.shownMs);
  const fin = r.lat.filter((l) => !l.interactive).map((l) => l.shownMs);
  console.log(`parallel coordinates: ${rows} lines, ${r.moves.length} brush moves: input to next frame median ${median(r.moves).toFixed(1)} ms, 90th percentile ${pct(r.moves, 0.9).toFixed(1)} ms; longest task ${r.longest.toFixed(0)} ms`);
  console.log(`brush to updated frame at 512x512: interactive states (n=${inter.length}) median ${median(inter).toFixed(0)} ms; final states, first pass (n=${fin.length}) median ${median(fin).toFixed(0)} ms`);
  const arrive = r.lat.filter((l) => l.interactive).map((l) => l.firstFrameMs), onScreen = r.lat.filter((l) => l.interactive).map((l) => l.shownMs - l.firstFrameMs);
  console.log(`  interactive states: send to frame received median ${median(arrive).toFixed(0)} ms (server), received to on screen median ${median(onScreen).toFixed(0)} ms, 90th percentile ${pct(onScreen, 0.9).toFixed(0)} ms (browser)`);
  const finArrive = r.lat.filter((l) => !l.interactive).map((l) => l.firstFrameMs), finOnScreen = r.lat.filter((l) => !l.interactive).map((l) => l.shownMs - l.firstFrameMs);
  console.log(`  final states: send to first frame received median ${median(finArrive).toFixed(0)} ms (server), received to on screen median ${median(finOnScreen).toFixed(0)} ms (browser)`);
  console.log(`last frame: level ${r.last.level}, ${r.last.stats?.passMs?.toFixed(1)} ms/pass, ${(r.last.stats?.samplesPerSecond / 1e6).toFixed(1)} M samples/s`);
  if (screenshot) {
    await page.evaluate(() => {
      const s = window.__raypc.state();
      window.__raypc.setState({ ...s, step: 6, image: { width: 512, height: 280 }, brushes: [{ name: 'temperature anomaly', min: 120, max: 700 }] });
    });
    await waitConverged(page, 60000);
    await page.screenshot({ path: screenshot });
    console.log(`screenshot ${screenshot}`);
  }
} finally {
  await context.close();
  server.kill('SIGTERM');
  rmSync(profile, { recursive: true, force: true });
}
