// Measurements of the UI on a real dataset (not part of ctest; speed is reported, not asserted):
//   node tests/browser/measure.mjs RAYPC DATASET [SCREENSHOT.png] [--play FPS[,FPS...] [--seconds S] [--only-play]]
//                                  [--server-log FILE]   (the server's log, for where the time goes)
//                                  [--assets DIR]        (another build of the UI, for A/B runs)
//                                  [--size WxH|view]     (the state's image size; default 512x512; view: the 3D view's own)
//                                  [--viewport WxH]      (the browser window; default 1280x860)
//                                  [--orbit S]           (5. below)
//                                  [--gpu]               (GPU compositing on SwiftShader, as browser.gpu.* run, instead of
//                                                         --disable-gpu's software compositing, which reads the 3D
//                                                         view's WebGL canvas back every frame: docs/ui.md)
//                                  [--reproject auto|on|off] (the 3D view's Re-project setting; default auto: off
//                                                         where WebGL runs in software, as here)
//                                  [--profile FILE]      (the page's CPU profiles while brushing, orbiting and playing: FILE.brushing.cpuprofile …)
// 1. brush-to-updated-frame latency at --size (512x512): a brush on the temperature axis is dragged with
//    the mouse; for every state the brush sent, the time from sending it to its first frame on
//    screen (decoded and drawn), separately for interactive states (while dragging) and the final
//    state (on release).
// 2. parallel-coordinates responsiveness with the dataset's sample (100 000 lines by default):
//    for each mouse move of a brush, the time from the input event to the next animation frame
//    (parcoord-es filters every line and starts redrawing inside that frame), and the longest task.
// 3. optionally a screenshot of the whole UI.
// 4. with --play FPS: playback at --size at FPS steps/s (the UI's speed menu; several, comma-separated,
//    one after the other) for S seconds (default 10): steps shown per second; per step the time from
//    the state sent to its first frame received and to its frame on screen (a period later: the step
//    is rendered while the one before it shows); and the level, size and pass of the frames shown.
//    --only-play skips 1-3.
// 0. always: the first picture, from the page's navigation to its first frame on screen and to the
//    first converged frame (at the view's own size: measured before --size applies).
// 5. with --orbit S: the camera dragged on the 3D view for S seconds (a pointer move every display
//    frame): frames received and shown per second, their levels, sizes and drawing buffers; per
//    frame where the time went (sent -> received -> shown); the CPU the server and chromium's
//    processes used meanwhile (Linux: /proc; every chromium on the machine counts); then the same
//    orbit over the protocol alone, without the page (node 20: run node with --experimental-websocket).
//    The orbit starts once the parallel coordinates' lines are drawn (their first drawing after the
//    page opens takes seconds of background slices).
// 6. with --slices S: the Map & section tab shown and the map's depth slider dragged for S seconds
//    (an input event every 33 ms across the mantle and back): maps shown per second and their size
//    in device pixels (the pane's; --viewport sets it), and the 3D view's frames meanwhile (it marks
//    the depth).
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import { join } from 'node:path';
import { createWriteStream, existsSync, mkdtempSync, readdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { availableParallelism, tmpdir } from 'node:os';
import { binaryHeader, chromiumArgs, chromiumPath, repoRoot, waitConverged } from './harness.mjs';

const args = process.argv.slice(2);
const flag = (name) => { const i = args.indexOf(name); return i < 0 ? null : args.splice(i, ['--only-play', '--gpu'].includes(name) ? 1 : 2).at(-1); };
const sizeFlag = flag('--size') ?? '512x512';
const size = sizeFlag === 'view' ? null : sizeFlag.split('x').map(Number);
const viewport = (flag('--viewport') ?? '1280x860').split('x').map(Number);
const orbitSeconds = Number(flag('--orbit') ?? 0);
const sliceSeconds = Number(flag('--slices') ?? 0);
let sizeText = ''; // the state's image size measured at
const serverLog = flag('--server-log'), assets = flag('--assets') ?? join(repoRoot, 'web', 'dist-test');
const profileFile = flag('--profile');
const gpu = flag('--gpu') !== null;
const reproject = flag('--reproject') ?? 'auto';
const playFps = flag('--play'), playSeconds = Number(flag('--seconds') ?? 10), onlyPlay = flag('--only-play') !== null;
const [raypc, dataset, screenshot] = args;
const { chromium } = createRequire(join(repoRoot, 'web', 'package.json'))('playwright-core');
const median = (a) => { const s = [...a].sort((x, y) => x - y); return s.length ? s[Math.floor(s.length / 2)] : NaN; };
const pct = (a, p) => { const s = [...a].sort((x, y) => x - y); return s[Math.min(s.length - 1, Math.floor(s.length * p))]; };

const server = spawn(raypc, ['serve', dataset, '--port', '0', '--assets', assets], { stdio: ['ignore', 'pipe', 'inherit'] });
const url = await new Promise((resolve, reject) => {
  let out = '';
  if (serverLog) server.stdout.pipe(createWriteStream(serverLog));
  server.stdout.on('data', (d) => { out += d; const m = /(http:\/\/127\.0\.0\.1:\d+\/)/.exec(out); if (m) resolve(m[1]); });
  server.on('exit', (c) => reject(new Error(`raypc serve exited with ${c}`)));
});
const profile = mkdtempSync(join(tmpdir(), 'raypc-measure-'));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: chromiumPath, headless: true, viewport: { width: viewport[0], height: viewport[1] },
  args: chromiumArgs(gpu),
});
try {
  await context.addInitScript(() => { window.__raypcTestHooks = true; }); // web/src/test_hooks.ts
  await context.addInitScript((v) => localStorage.setItem('raypc.reproject', v), reproject);
  const page = await context.newPage();
  await page.goto(url);
  await page.waitForFunction(() => window.__raypc && window.__raypc.parcoords.rowCount > 0 && window.__raypc.headers.length > 0, null, { timeout: 60000 });
  await waitConverged(page, 60000);
  const first = await page.evaluate(() => ({ shown: window.__raypc.shownLog[0], converged: performance.now(), image: window.__raypc.state().image }));
  console.log(`first picture at ${first.image.width}x${first.image.height} (window ${viewport.join('x')}): on screen ${first.shown.t.toFixed(0)} ms after navigation (level ${first.shown.level}, ${first.shown.width}x${first.shown.height}), converged by ${first.converged.toFixed(0)} ms`);
  if (size) {
    await page.evaluate(([width, height]) => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, image: { width, height } }); }, size);
    await waitConverged(page, 60000);
  }
  sizeText = size ? size.join('x') : `${first.image.width}x${first.image.height}`;
  if (orbitSeconds > 0) await measureOrbit(page);
  if (sliceSeconds > 0) await measureSlices(page);
  const rows = await page.evaluate(() => window.__raypc.parcoords.rowCount);
  if (!onlyPlay) await brushAndScreenshot(page, rows);
  if (playFps) for (const fps of playFps.split(',')) await measurePlayback(page, Number(fps));
} finally {
  await context.close();
  server.kill('SIGTERM');
  rmSync(profile, { recursive: true, force: true });
}

async function measureOrbit(page) {
  const box = await page.evaluate(() => { const r = document.getElementById('view3d').getBoundingClientRect(); return { x: r.x, y: r.y, w: r.width, h: r.height }; });
  const cx = box.x + box.w / 2, cy = box.y + box.h / 2;
  const linesMs = await page.evaluate(() => new Promise((resolve) => {
    const t0 = performance.now();
    const poll = () => window.__raypc.parcoords.timing.drawnAt.foreground > 0 ? resolve(performance.now() - t0) : setTimeout(poll, 50);
    poll();
  }));
  if (linesMs > 100) console.log(`  (waited ${(linesMs / 1000).toFixed(1)} s for the parallel coordinates' lines before the orbit)`);
  await page.mouse.move(cx, cy);
  const since = await page.evaluate(() => ({ headers: window.__raypc.frameLog.length, shown: window.__raypc.shownLog.length, t: performance.now() }));
  const cdp = await startProfile(page);
  const cpuBefore = cpuTimes();
  await page.mouse.down();
  // The pointer moves at the display's rate, as a hand on a mouse does: after the (trusted) press,
  // the page dispatches a pointermove of that pointer on every animation frame. (Moves driven one
  // by one from here arrive at the rate of the driver's round trips, about 9/s on a loaded machine,
  // which then bounds the frames.)
  const moves = await page.evaluate(([x0, y0, ms]) => new Promise((resolve) => {
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
  }), [cx, cy, orbitSeconds * 1000]);
  const r = await page.evaluate((n) => ({
    sent: window.__raypc.sentLog.filter((e) => e.t >= n.t),
    received: window.__raypc.frameLog.slice(n.headers).filter((f) => f.t >= n.t),
    shown: window.__raypc.shownLog.slice(n.shown).filter((f) => f.t >= n.t),
    now: performance.now(),
  }), since);
  const cpuAfter = cpuTimes();
  await stopProfile(cdp, 'orbit');
  await page.mouse.up();
  await waitConverged(page, 60000);
  const seconds = (r.now - since.t) / 1000;
  const count = (list, key) => { const c = {}; for (const s of list) c[key(s)] = (c[key(s)] ?? 0) + 1; return JSON.stringify(c); };
  const gl = await page.evaluate(() => ({ reproject: document.getElementById('reproject').value, note: document.getElementById('reprojectNote').textContent }));
  console.log(`re-project ${gl.reproject} ${gl.note}`);
  console.log(`orbit for ${seconds.toFixed(1)} s at ${sizeText}: ${(r.received.length / seconds).toFixed(1)} frames/s received, ${(r.shown.length / seconds).toFixed(1)} shown; shown by level ${count(r.shown, (s) => s.level)}, by size ${count(r.shown, (s) => `${s.width}x${s.height}`)}, drawn into a buffer of ${count(r.shown, (s) => (s.buffer ?? ['?']).join('x'))}; ${(moves / seconds).toFixed(1)} pointer moves/s driven`);
  // Where a round trip goes: state sent -> its frame received (the server and the socket), frame
  // received -> on screen (decoded and drawn), frame received -> the next state sent (the page).
  const sentAt = new Map(r.sent.map((e) => [e.id, e.t])), shownAt = new Map(r.shown.map((s) => [s.id, s.t]));
  const trip = [], show = [], next = [];
  for (const f of r.received) {
    if (sentAt.has(f.id)) trip.push(f.t - sentAt.get(f.id));
    if (shownAt.has(f.id)) show.push(shownAt.get(f.id) - f.t);
    const after = r.sent.find((e) => e.t >= f.t);
    if (after) next.push(after.t - f.t);
  }
  const ms = (a) => `median ${median(a).toFixed(0)}, 90 % ${pct(a, 0.9).toFixed(0)} ms`;
  console.log(`  per frame: sent -> received ${ms(trip)}; received -> shown ${ms(show)}; received -> next state sent ${ms(next)}`);
  if (cpuBefore && cpuAfter) {
    const used = [...cpuAfter].map(([k, v]) => [k, (v - (cpuBefore.get(k) ?? 0)) / seconds]).filter(([, v]) => v >= 0.005);
    const server = serverSeconds(cpuBefore, cpuAfter) * 1000 / r.received.length;
    console.log(`  CPU meanwhile (cores of ${availableParallelism()}; the server ${server.toFixed(0)} ms a frame received): ${used.sort((a, b) => b[1] - a[1]).map(([k, v]) => `${k} ${v.toFixed(2)}`).join(', ')}`);
  }
  await orbitWithoutPage(page, seconds);
}

// CPU seconds used so far by the server and by chromium's processes, summed by chromium's
// process type (--type=gpu-process, renderer, ...; the browser process has none), from /proc;
// null where there is no /proc.
function cpuTimes() {
  if (!existsSync('/proc/self/stat')) return null;
  const ticks = 100; // USER_HZ, 100 on Linux
  const times = new Map();
  for (const pid of readdirSync('/proc').filter((d) => /^\d+$/.test(d))) {
    try {
      const cmd = readFileSync(`/proc/${pid}/cmdline`, 'utf8').split(/[\0 ]/); // chromium rewrites its own
      const name = Number(pid) === server.pid ? 'raypc serve'
        : cmd[0].includes('chrom') ? `chromium ${(cmd.find((a) => a.startsWith('--type=')) ?? '--type=browser').slice(7)}` : null;
      if (!name) continue;
      const stat = readFileSync(`/proc/${pid}/stat`, 'utf8');
      const f = stat.slice(stat.lastIndexOf(')') + 2).split(' '); // fields from the 3rd on
      times.set(name, (times.get(name) ?? 0) + (Number(f[11]) + Number(f[12])) / ticks); // utime + stime
    } catch { /* the process ended meanwhile */ }
  }
  return times;
}

// The server's CPU seconds between two cpuTimes().
function serverSeconds(before, after) {
  return after.get('raypc serve') - before.get('raypc serve');
}

// The same orbit driven over the protocol alone (no page decoding and drawing beside the server):
// the page's state with the camera turning, one interactive state in flight as the page keeps it,
// each sent as soon as the previous one's frame has arrived. What the server can deliver; needs
// node's WebSocket (node 22, or node 20 with --experimental-websocket).
async function orbitWithoutPage(page, seconds) {
  if (typeof WebSocket === 'undefined') {
    console.log('  (without the page: skipped, run node with --experimental-websocket)');
    return;
  }
  const state = await page.evaluate(() => window.__raypc.state());
  const ws = new WebSocket(url.replace('http', 'ws') + 'ws');
  ws.binaryType = 'arraybuffer';
  const sizes = {};
  let id = 0, frames = 0, t0 = 0, cpu0 = null;
  const send = () => {
    const camera = { ...state.camera, azimuthDeg: (state.camera.azimuthDeg + 2 * ++id) % 360 };
    ws.send(JSON.stringify({ type: 'state', id, state: { ...state, camera }, interactive: true, playback: false }));
  };
  await new Promise((resolve, reject) => {
    ws.onerror = () => reject(new Error('orbit without the page: the WebSocket failed'));
    ws.onopen = () => ws.send(JSON.stringify({ type: 'hello', protocol: 1 }));
    ws.onmessage = (ev) => {
      if (typeof ev.data === 'string') {
        const m = JSON.parse(ev.data);
        if (m.type === 'hello') { t0 = performance.now(); cpu0 = cpuTimes(); send(); }
        else if (m.type === 'error') reject(new Error(`orbit without the page: ${m.message}`));
        return;
      }
      const h = binaryHeader(ev.data).header;
      if (h.id !== id) return;
      frames++;
      const key = `level ${h.level} ${h.width}x${h.height}`;
      sizes[key] = (sizes[key] ?? 0) + 1;
      if (performance.now() - t0 < seconds * 1000) send();
      else resolve();
    };
  });
  const cpu1 = cpuTimes();
  ws.close();
  const s = (performance.now() - t0) / 1000;
  const server = cpu0 && cpu1 ? `; the server used ${(serverSeconds(cpu0, cpu1) / s).toFixed(2)} cores, ${(serverSeconds(cpu0, cpu1) * 1000 / frames).toFixed(0)} ms a frame` : '';
  console.log(`  without the page (the same states over the protocol, one in flight): ${(frames / s).toFixed(1)} frames/s received; ${JSON.stringify(sizes)}${server}`);
}

async function measureSlices(page) {
  await page.click('#pcTabSlices');
  await page.waitForFunction(() => window.__raypc.slices.map.shown > 0, null, { timeout: 60000 });
  const since = await page.evaluate(() => ({ maps: window.__raypc.slices.map.shown, shown: window.__raypc.shownLog.length, t: performance.now() }));
  const t0 = Date.now();
  for (let i = 0; Date.now() - t0 < sliceSeconds * 1000; i++) {
    await page.evaluate((k) => {
      const slider = document.getElementById('mapDepth');
      const lo = Number(slider.min), hi = Number(slider.max), phase = (k % 120) / 60;
      slider.value = String(Math.round(lo + (hi - lo) * (phase < 1 ? phase : 2 - phase)));
      slider.dispatchEvent(new Event('input'));
    }, i);
    await page.waitForTimeout(33);
  }
  const r = await page.evaluate((n) => ({
    maps: window.__raypc.slices.map.shown - n.maps, header: window.__raypc.slices.map.header,
    shown: window.__raypc.shownLog.length - n.shown, now: performance.now(),
  }), since);
  const seconds = (r.now - since.t) / 1000;
  console.log(`depth dragged for ${seconds.toFixed(1)} s: ${(r.maps / seconds).toFixed(1)} maps/s shown at ${r.header.width}x${r.header.height} (window ${viewport.join('x')}); the 3D view meanwhile ${(r.shown / seconds).toFixed(1)} frames/s`);
  if (screenshot) {
    // The tab at 660 km, for docs/maps.md: SCREENSHOT with -slices before .png.
    await page.fill('#mapDepthValue', '660');
    await page.press('#mapDepthValue', 'Enter');
    await page.evaluate(() => document.getElementById('sliceSection').scrollIntoView());
    await page.waitForTimeout(1500);
    await waitConverged(page, 60000);
    await page.screenshot({ path: screenshot.replace(/(\.png)?$/, '-slices.png') });
  }
}

async function measurePlayback(page, playFps) {
  const nSteps = await page.evaluate(() => window.__raypc.info.steps.length);
  await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, step: 0 }); });
  await waitConverged(page, 60000);
  await page.selectOption('#fps', String(playFps));
  const since = await page.evaluate(() => ({ sent: window.__raypc.sentLog.length, lat: window.__raypc.latencies.length,
    headers: window.__raypc.headers.length, shown: window.__raypc.shownLog.length }));
  await page.evaluate(() => {
    window.__playTasks = [];
    new PerformanceObserver((l) => { for (const e of l.getEntries()) window.__playTasks.push(e.duration); }).observe({ type: 'longtask', buffered: false });
  });
  const cdp = await startProfile(page);
  const t0 = Date.now();
  await page.click('#play');
  await page.waitForTimeout(playSeconds * 1000);
  await page.click('#play');
  await stopProfile(cdp, 'playback');
  const seconds = (Date.now() - t0) / 1000;
  const r = await page.evaluate((n) => ({
    sent: window.__raypc.sentLog.slice(n.sent).filter((e) => e.playback),
    lat: window.__raypc.latencies.slice(n.lat).filter((l) => l.playback),
    headers: window.__raypc.headers.slice(n.headers).filter((h) => h.playback),
    shown: window.__raypc.shownLog.slice(n.shown).filter((h) => h.playback),
    tasks: window.__playTasks,
  }), since);
  // From a step's frame on screen to the next step sent: the UI's own time (and the speed's wait).
  const gaps = [];
  for (let i = 0; i + 1 < r.sent.length; i++) {
    const l = r.lat.find((x) => x.id === r.sent[i].id);
    if (l) gaps.push(r.sent[i + 1].t - (r.sent[i].t + l.shownMs));
  }
  const levels = {};
  for (const h of r.headers) levels[h.level] = (levels[h.level] ?? 0) + 1;
  const passMs = r.headers.map((h) => h.stats?.passMs ?? 0);
  // The rate between the first and the last step sent (the wall time also holds the clicks' round trips).
  const span = r.sent.length > 1 ? (r.sent.at(-1).t - r.sent[0].t) / 1000 : NaN;
  console.log(`playback of ${nSteps} steps at ${playFps} steps/s asked, ${sizeText}, ${seconds.toFixed(1)} s: ${r.sent.length} steps sent, ${((r.sent.length - 1) / span).toFixed(2)} steps/s (${(r.sent.length / seconds).toFixed(2)} over the wall time)`);
  console.log(`  per step: sent to frame received median ${median(r.lat.map((l) => l.firstFrameMs)).toFixed(0)} ms, 90th percentile ${pct(r.lat.map((l) => l.firstFrameMs), 0.9).toFixed(0)} ms; received to on screen median ${median(r.lat.map((l) => l.shownMs - l.firstFrameMs)).toFixed(0)} ms`);
  console.log(`  frame on screen to the next step sent: median ${median(gaps).toFixed(0)} ms, 90th percentile ${pct(gaps, 0.9).toFixed(0)} ms; long tasks ${r.tasks.length}, ${r.tasks.reduce((a, b) => a + b, 0).toFixed(0)} ms in all, longest ${Math.max(0, ...r.tasks).toFixed(0)} ms`);
  console.log(`  server pass median ${median(passMs).toFixed(0)} ms; frames received by level ${JSON.stringify(levels)}`);
  const shownBy = (key) => { const c = {}; for (const s of r.shown) c[key(s)] = (c[key(s)] ?? 0) + 1; return JSON.stringify(c); };
  console.log(`  frames shown: ${r.shown.length}; by level ${shownBy((s) => s.level)}; by size ${shownBy((s) => `${s.width}x${s.height}`)}; by pass ${shownBy((s) => s.pass)}`);
}

// With --profile: a CPU profile of the page from startProfile to stopProfile, written whole to
// FILE with the phase's name before its extension, and the functions with the most self time.
async function startProfile(page) {
  if (!profileFile) return null;
  const cdp = await page.context().newCDPSession(page);
  await cdp.send('Profiler.enable');
  await cdp.send('Profiler.setSamplingInterval', { interval: 200 });
  await cdp.send('Profiler.start');
  return cdp;
}

async function stopProfile(cdp, phase) {
  if (!cdp) return;
  const { profile } = await cdp.send('Profiler.stop');
  await cdp.detach();
  const file = profileFile.replace(/(\.[^./]*)?$/, (ext) => `.${phase}${ext}`);
  writeFileSync(file, JSON.stringify(profile));
  const self = new Map(), byId = new Map(profile.nodes.map((n) => [n.id, n]));
  const dt = profile.timeDeltas, total = (profile.endTime - profile.startTime) / 1000;
  for (let i = 0; i < profile.samples.length; i++) {
    const f = byId.get(profile.samples[i]).callFrame;
    const key = `${f.functionName || '(anonymous)'} ${f.url.split('/').at(-1)}:${f.lineNumber + 1}`;
    self.set(key, (self.get(key) ?? 0) + (dt[i + 1] ?? 0) / 1000);
  }
  const top = [...self].sort((a, b) => b[1] - a[1]).slice(0, 15);
  console.log(`  CPU profile of the page during ${phase} (${total.toFixed(0)} ms, written to ${file}), self time:`);
  for (const [k, ms] of top) console.log(`    ${ms.toFixed(0).padStart(6)} ms  ${k}`);
}

async function brushAndScreenshot(page, rows) {

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
  const cdp = await startProfile(page);
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
  await stopProfile(cdp, 'brushing');
  const r = await page.evaluate((n) => ({ lat: window.__raypc.latencies.slice(n), moves: window.__moves, longest: window.__longest, last: window.__raypc.headers.at(-1) }), since);
  const inter = r.lat.filter((l) => l.interactive).map((l) => l.shownMs);
  const fin = r.lat.filter((l) => !l.interactive).map((l) => l.shownMs);
  console.log(`parallel coordinates: ${rows} lines, ${r.moves.length} brush moves: input to next frame median ${median(r.moves).toFixed(1)} ms, 90th percentile ${pct(r.moves, 0.9).toFixed(1)} ms; longest task ${r.longest.toFixed(0)} ms`);
  console.log(`brush to updated frame at ${sizeText}: interactive states (n=${inter.length}) median ${median(inter).toFixed(0)} ms; final states, first pass (n=${fin.length}) median ${median(fin).toFixed(0)} ms`);
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
}
