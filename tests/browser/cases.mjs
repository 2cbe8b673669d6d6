// End-to-end browser tests of the UI against the real server:
//   node tests/browser/cases.mjs CASE RAYPC FIXTURE_DIR
// CASE: brush | warp | play | save_load | two_tabs | presets | pathlines | resolution | context | colours |
// brush_values | multi_brush | axes | camera | responsive | stereo | light | persistence | link |
// colours_unmistakable [gpu].
// Each case starts its own server and browser.
import { readFileSync, writeFileSync } from 'node:fs';
import { spawnSync } from 'node:child_process';
import { basename, dirname, join } from 'node:path';
import { binaryHeader, check, meanAbsDiff, openUi, postJson, runCase, standardView, TestFailure, viewPixels, volumeOnly, waitConverged } from './harness.mjs';

// A fourth argument `gpu` runs chromium with GPU rasterisation on a software GL (SwiftShader), as a
// machine without a GPU does, instead of --disable-gpu (ctest runs the drawing-heavy cases both ways: tests/browser/CMakeLists.txt).
const [caseName, raypc, fixture, mode] = process.argv.slice(2);

const frames = () => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
const rState = (page) => page.evaluate(() => window.__raypc.state());

// Screen box of the brush area of one parallel-coordinates axis.
async function axisBox(page, name) {
  const box = await page.evaluate((axis) => {
    for (const g of document.querySelectorAll('#parcoords svg g.dimension')) {
      if (g.__data__ !== axis) continue;
      const r = g.querySelector('.brush .overlay')?.getBoundingClientRect();
      if (r) return { x: r.x, y: r.y, width: r.width, height: r.height };
    }
    return null;
  }, name);
  if (!box) throw new TestFailure(`no brushable axis '${name}' in the parallel coordinates`);
  return box;
}

async function brushAxis(page, name, fromFraction, toFraction) {
  const b = await axisBox(page, name);
  const x = b.x + b.width / 2;
  await page.mouse.move(x, b.y + b.height * fromFraction);
  await page.mouse.down();
  for (let i = 1; i <= 8; i++) await page.mouse.move(x, b.y + b.height * (fromFraction + ((toFraction - fromFraction) * i) / 8));
  await page.mouse.up();
}

async function drag(page, dx, dy, { steps = 6, button = 'left' } = {}) {
  const r = await page.locator('#view3d').boundingBox();
  const x = r.x + r.width / 2, y = r.y + r.height / 2;
  await page.mouse.move(x, y);
  await page.mouse.down({ button });
  for (let i = 1; i <= steps; i++) await page.mouse.move(x + (dx * i) / steps, y + (dy * i) / steps);
  await page.mouse.up({ button });
}

const info = async (url) => (await fetch(url + 'api/info')).json();

// How many pixels of the 3D view are lit (brighter than the dark background).
const litPixels = (page) => page.evaluate(() => {
  const { data: d } = window.__viewImageData();
  let n = 0;
  for (let i = 0; i < d.length; i += 4) if (d[i] + d[i + 1] + d[i + 2] > 60) n++;
  return n;
});

// The Rendering section's Re-project set to on (auto is off on headless chromium's software GL).
const reprojectOn = (page) => page.evaluate(() => {
  const s = document.getElementById('reproject');
  s.value = 'on';
  s.dispatchEvent(new Event('change'));
});

// The rotation of unit quaternion q = [x, y, z, w] applied to v.
function rotate([x, y, z, w], v) {
  return [
    (1 - 2 * (y * y + z * z)) * v[0] + 2 * (x * y - z * w) * v[1] + 2 * (x * z + y * w) * v[2],
    2 * (x * y + z * w) * v[0] + (1 - 2 * (x * x + z * z)) * v[1] + 2 * (y * z - x * w) * v[2],
    2 * (x * z - y * w) * v[0] + 2 * (y * z + x * w) * v[1] + (1 - 2 * (x * x + y * y)) * v[2],
  ];
}

// A mock WebXR headset for headless chromium (an init script): with ?xrmock in the page's URL,
// navigator.xr offers immersive-vr; its session's animation frames run when the test calls
// __xrMock.tick(); the viewer pose has two eyes `ipd` metres apart about the head (position and yaw
// about +y in __xrMock.head) with the projection matrices of `frusta` ([left, right, down, up]
// tangents); the layer's framebuffer is null (the canvas) and its viewports are the canvas' halves.
// With ?noxr the browser has no navigator.xr.
function xrMock() {
  const q = new URLSearchParams(location.search);
  if (q.has('noxr')) {
    Object.defineProperty(Navigator.prototype, 'xr', { get: () => undefined, configurable: true });
    return;
  }
  if (!q.has('xrmock')) return;
  const mock = { head: { x: 0, y: 0, z: 0, yawDeg: 0 }, ipd: 0.2, frusta: { left: [-1.1, 0.9, -1, 1], right: [-0.9, 1.1, -1, 1] }, callbacks: [], ended: false };
  const projection = ([l, r, d, u]) => {
    const n = 0.1, f = 1000, m = new Float32Array(16);
    m[0] = 2 / (r - l); m[5] = 2 / (u - d); m[8] = (r + l) / (r - l); m[9] = (u + d) / (u - d);
    m[10] = -(f + n) / (f - n); m[11] = -1; m[14] = (-2 * f * n) / (f - n);
    return m;
  };
  const pose = () => {
    const h = mock.head, a = (h.yawDeg * Math.PI) / 180;
    return {
      views: ['left', 'right'].map((eye) => {
        const k = (eye === 'left' ? -0.5 : 0.5) * mock.ipd; // along the head's +x = (cos a, 0, -sin a)
        return { eye, transform: { position: { x: h.x + Math.cos(a) * k, y: h.y, z: h.z - Math.sin(a) * k, w: 1 },
          orientation: { x: 0, y: Math.sin(a / 2), z: 0, w: Math.cos(a / 2) } }, projectionMatrix: projection(mock.frusta[eye]) };
      }),
    };
  };
  class XRWebGLLayer {
    constructor(session, gl) { this.gl = gl; this.framebuffer = null; }
    getViewport(view) {
      const w = Math.floor(this.gl.canvas.width / 2), h = this.gl.canvas.height;
      return { x: view.eye === 'left' ? 0 : w, y: 0, width: w, height: h };
    }
  }
  const session = {
    listeners: [],
    requestReferenceSpace: async (type) => ({ type }),
    requestAnimationFrame: (cb) => mock.callbacks.push(cb),
    updateRenderState: (s) => { session.renderState = s; },
    end: async () => { mock.ended = true; for (const l of session.listeners) l(); },
    addEventListener: (type, l) => { if (type === 'end') session.listeners.push(l); },
  };
  mock.tick = () => {
    const callbacks = mock.callbacks;
    mock.callbacks = [];
    for (const cb of callbacks) cb(performance.now(), { getViewerPose: () => pose() });
  };
  window.XRWebGLLayer = XRWebGLLayer;
  // Chromium's own makeXRCompatible waits for a device that is not there.
  WebGL2RenderingContext.prototype.makeXRCompatible = async () => {};
  const xr = {
    isSessionSupported: async (mode) => mode === 'immersive-vr',
    requestSession: async (mode) => { mock.ended = false; mock.callbacks = []; session.listeners = []; mock.mode = mode; return session; },
  };
  Object.defineProperty(Navigator.prototype, 'xr', { get: () => xr, configurable: true });
  window.__xrMock = mock;
}

// The size of a PNG file's image.
function pngSize(file) {
  const bytes = readFileSync(file);
  check(bytes.subarray(1, 4).toString() === 'PNG', `${file} is not a PNG`);
  return { width: bytes.readUInt32BE(16), height: bytes.readUInt32BE(20) };
}

// Opens the screenshot dialog, picks `choice` (view, 2x, 4k, custom [w, h]) and saves the PNG.
async function screenshot(page, file, choice = 'view', custom = null) {
  await page.click('#screenshot');
  await page.check(`input[name="shotSize"][value="${choice}"]`);
  if (custom) {
    await page.fill('#shotWidth', String(custom[0]));
    await page.fill('#shotHeight', String(custom[1]));
  }
  const [shot] = await Promise.all([page.waitForEvent('download', { timeout: 90000 }), page.click('#shotRender')]);
  await shot.saveAs(file);
  return pngSize(file);
}

const cases = {
  // Brushing an axis with the mouse sends its range to the server (the state of the frame shown
  // carries it), the exact selected volume is shown and agrees with the server and with the
  // analytic shell volume, and the image changes; clearing the brush brings the image back.
  async brush({ context, url }) {
    const page = await openUi(context, url);
    // With no brush the lines are not veiled (the brushed layer is empty); a brush veils them.
    const veil = () => page.evaluate(() => {
      const c = document.querySelector('#parcoords canvas.brushed');
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++;
      return n / (c.width * c.height);
    });
    await page.waitForFunction(() => window.__raypc.parcoords.timing.lines.foreground > 0, null, { timeout: 10000 }).catch(() => {});
    const unbrushed = await veil();
    check(unbrushed === 0, `with no brush ${(100 * unbrushed).toFixed(1)} % of the brushed layer is painted (a veil over every line)`);

    await standardView(page);
    const before = await viewPixels(page);
    const ds = await info(url);
    const radius = ds.coordinates.find((c) => c.name === 'radius');
    check(radius && radius.units === 'km', `/api/info has no radius coordinate in km: ${JSON.stringify(ds.coordinates)}`);
    // A title's lines (tspans: long titles wrap) joined as one text.
    const titles = () => page.evaluate(() => [...document.querySelectorAll('#parcoords svg .label')]
      .map((e) => ([...e.querySelectorAll('tspan')].map((t) => t.textContent).join(' ') || e.textContent).replace(/- /g, '-')));
    // x, y, z and radius are hidden by default; the Axes menu shows radius.
    const hidden = ['x', 'y', 'z', 'radius'];
    const shownBefore = await titles();
    check(shownBefore.length === ds.sample.columns.length - hidden.length && !shownBefore.includes('radius [km]'),
      `${shownBefore.length} axes shown by default (${shownBefore.join(', ')}), expected every sample column but ${hidden.join(', ')}`);
    await page.click('#axisMenu summary');
    await page.check('#axisChoice input[data-axis="radius"]');
    await page.click('#axisMenu summary');
    await page.waitForFunction(() => [...document.querySelectorAll('#parcoords svg .label')].some((e) => [...e.querySelectorAll('tspan')].map((t) => t.textContent).join(' ') === 'radius [km]'), null, { timeout: 5000 })
      .catch(() => { throw new TestFailure('ticking radius under Axes did not show its axis'); });
    const title = await titles();
    check(title.includes('radius [km]') && title.some((t) => /^temperature \[K\]$/.test(t)), `axis titles lack units: ${title.join(', ')}`);
    // Units as src/render/display_units.json writes them (the legends of pictures too).
    // A long title may wrap and end in "…": the whole is the axis' ARIA label.
    const spin = await page.evaluate(() => [...document.querySelectorAll('#parcoords g.dimension')].find((g) => g.__data__.startsWith('spin'))?.getAttribute('aria-label') ?? '');
    check(title.includes('lat [°N]') && title.includes('lon [°E]') && spin.startsWith('spin transition-induced density anomaly [kg/m³]'),
      `axis titles do not write units as display_units.json says: ${title.join(', ')}; ${spin}`);
    check(title.length === shownBefore.length + 1, `${title.length} axes after showing radius, expected ${shownBefore.length + 1}`);

    await brushAxis(page, 'radius', 0.5, 0.95);
    await page.waitForFunction(() => window.__raypc.parcoords.timing.lines.brushed > 0, null, { timeout: 10000 }).catch(() => {});
    const brushedVeil = await veil();
    check(brushedVeil > 0.9, `with a brush only ${(100 * brushedVeil).toFixed(1)} % of the brushed layer is veiled`);
    const s = await rState(page);
    check(s.brushes.length === 1 && s.brushes[0].name === 'radius', `state.brushes after brushing radius: ${JSON.stringify(s.brushes)}`);
    const { min, max } = s.brushes[0];
    check(min > radius.min && max < radius.max && max - min > 0.2 * (radius.max - radius.min),
      `radius brush ${min}..${max} does not match the dragged 50 %..95 % of ${radius.min}..${radius.max}`);
    const interactiveSent = await page.evaluate(() => window.__raypc.sentLog.filter((e) => e.interactive && e.brushes.length).length);
    check(interactiveSent >= 1, 'no interactive state was sent while brushing');
    // Releasing the brush redraws every line (and asks for the exact selection and the statistics),
    // but only once the still frame it asked for is shown.
    const finalId = await page.evaluate(() => window.__raypc.sentLog.filter((e) => !e.interactive).at(-1)?.id);
    await page.waitForFunction((id) => window.__raypc.afterFrames.some((a) => a.id === id), finalId, { timeout: 20000 });
    const deferred = await page.evaluate(() => window.__raypc.afterFrames);
    check(deferred.some((a) => a.id === finalId && a.afterShown),
      `the full line redraw did not wait for the frame of the released brush (state ${finalId}): ${JSON.stringify(deferred)}`);

    await waitConverged(page);
    const shown = await page.evaluate(() => {
      const r = window.__raypc;
      const h = r.headers[r.headers.length - 1];
      return { header: h, sent: r.sentLog.find((e) => e.id === h.id), selection: r.selection, text: document.getElementById('selectionValue')?.textContent };
    });
    check(shown.sent && JSON.stringify(shown.sent.brushes) === JSON.stringify(s.brushes),
      `the frame shown (id ${shown.header.id}) was not rendered from the brushed state: ${JSON.stringify(shown.sent)}`);
    const sel = shown.selection;
    check(sel && sel.fractionOfMantle > 0.05 && sel.fractionOfMantle < 0.95, `selected fraction ${JSON.stringify(sel)}`);
    const server = await postJson(url + 'api/selection', s);
    check(server.status === 200 && Math.abs(server.body.fractionOfMantle - sel.fractionOfMantle) < 1e-9,
      `UI shows ${sel.fractionOfMantle}, POST /api/selection says ${JSON.stringify(server.body)}`);
    const rc = radius.min, rs = radius.max;
    const analytic = (max ** 3 - min ** 3) / (rs ** 3 - rc ** 3);
    check(Math.abs(sel.fractionOfMantle - analytic) < 0.03, `selected fraction ${sel.fractionOfMantle} of the shell ${min}..${max} km, analytic ${analytic}`);
    const pct = (sel.fractionOfMantle * 100).toFixed(2);
    check(shown.text && shown.text.includes(`${pct} %`) && shown.text.includes('km³'), `selection text '${shown.text}' lacks ${pct} % and km³`);

    const after = await viewPixels(page);
    const d = meanAbsDiff(before, after);
    check(d > 2, `the image hardly changed after brushing (mean difference ${d.toFixed(2)} grey levels)`);

    await page.click('#clearBrushes');
    await waitConverged(page);
    check((await rState(page)).brushes.length === 0, 'brushes not cleared');
    await page.waitForTimeout(300);
    const clearedVeil = await veil();
    check(clearedVeil === 0, `after Clear brushes ${(100 * clearedVeil).toFixed(1)} % of the brushed layer still veils the lines`);
    const cleared = await viewPixels(page);
    const d2 = meanAbsDiff(before, cleared);
    check(d2 < 1, `after clearing the brush the image differs from the unbrushed one by ${d2.toFixed(2)}`);
  },

  // Headless chromium's WebGL runs in software (SwiftShader): Re-project's auto is off there and
  // says why; while a drag's frames are held nothing is drawn into the view (every draw would be
  // read back on the CPU the server needs), and each frame that then arrives is drawn once.
  // With Re-project on, while a new frame is on its way the last one is re-projected with the
  // current camera, and the warped picture is closer to the new frame than the unwarped old one
  // (the camera math agrees with the server's).
  async warp({ context, url }) {
    const page = await openUi(context, url);
    await standardView(page);
    await volumeOnly(page);
    await waitConverged(page);
    // A value the setting does not know, kept by the browser (an older or edited one), is auto.
    await page.evaluate(() => localStorage.setItem('raypc.reproject', 'sideways'));
    await page.reload();
    await page.waitForFunction(() => window.__raypc && window.__raypc.headers.length > 0, null, { timeout: 30000 });
    await waitConverged(page);
    const gl = await page.evaluate(() => ({ value: document.getElementById('reproject').value, note: document.getElementById('reprojectNote').textContent }));
    check(gl.value === 'auto' && /^\(off: WebGL runs in software, .*SwiftShader/.test(gl.note), `Re-project on a software GL: ${JSON.stringify(gl)}`);
    {
      const old = await viewPixels(page);
      const before = await page.evaluate(() => ({ draws: window.__raypc.view.glDraws, shown: window.__raypc.lastShownId }));
      await page.evaluate(() => { window.__raypc.holdFrames = true; });
      await drag(page, 45, 20);
      await page.evaluate(frames);
      const held = await viewPixels(page);
      const during = await page.evaluate(() => ({ draws: window.__raypc.view.glDraws, shown: window.__raypc.lastShownId, sent: window.__raypc.lastSentId }));
      check(during.draws === before.draws && during.shown === before.shown && during.sent > during.shown,
        `re-projection off: the view was drawn while a drag's frames were held (${JSON.stringify({ before, during })})`);
      check(meanAbsDiff(old, held) < 0.01, `re-projection off: the view changed while no frame arrived (${meanAbsDiff(old, held).toFixed(3)})`);
      const n = await page.evaluate(() => window.__raypc.view.framesShown);
      await page.evaluate(() => window.__raypc.releaseFrames());
      await waitConverged(page);
      const after = await page.evaluate((k) => ({ draws: window.__raypc.view.glDraws, frames: window.__raypc.view.framesShown - k }), n);
      check(after.frames >= 1 && after.draws - during.draws <= after.frames + 2,
        `re-projection off: ${after.draws - during.draws} draws for ${after.frames} frames shown`);
      const fresh = await viewPixels(page);
      check(meanAbsDiff(old, fresh) > 1.5, `re-projection off: the new frame hardly differs from the old (${meanAbsDiff(old, fresh).toFixed(2)})`);
      console.log(`  re-projection off ${gl.note}: no draw while frames were held; ${after.draws - during.draws} draws for ${after.frames} frames after`);
    }
    await reprojectOn(page);
    check(await page.evaluate(() => document.getElementById('reprojectNote').textContent === ''), 'Re-project on still shows the note of auto');
    await waitConverged(page);
    for (const [label, act] of [
      ['orbit', () => drag(page, 45, 20)],
      ['zoom', async () => {
        const r = await page.locator('#view3d').boundingBox();
        await page.mouse.move(r.x + r.width / 2, r.y + r.height / 2);
        await page.mouse.wheel(0, -250);
      }],
      ['pan', () => drag(page, 40, -25, { button: 'right' })],
    ]) {
      const old = await viewPixels(page);
      const before = await page.evaluate(() => ({ warped: window.__raypc.warpedWhileWaiting, shown: window.__raypc.lastShownId }));
      await page.evaluate(() => { window.__raypc.holdFrames = true; });
      await act();
      await page.evaluate(frames);
      const warped = await viewPixels(page);
      const during = await page.evaluate(() => ({ warped: window.__raypc.warpedWhileWaiting, shown: window.__raypc.lastShownId, sent: window.__raypc.lastSentId }));
      check(during.warped > before.warped, `${label}: no warped draw while the new frame was pending (${JSON.stringify(during)})`);
      check(during.shown === before.shown && during.sent > during.shown, `${label}: a new frame was shown while frames were held: ${JSON.stringify(during)}`);
      await page.evaluate(() => window.__raypc.releaseFrames());
      await page.waitForTimeout(label === 'zoom' ? 400 : 0); // the wheel's final state follows after 250 ms
      await waitConverged(page);
      const fresh = await viewPixels(page);
      const dOld = meanAbsDiff(old, fresh), dWarp = meanAbsDiff(warped, fresh);
      check(dOld > 1.5, `${label}: the camera change hardly changed the image (${dOld.toFixed(2)})`);
      check(dWarp < 0.5 * dOld, `${label}: the warped view (difference ${dWarp.toFixed(2)}) is not much closer to the new frame than the old frame (${dOld.toFixed(2)})`);
      console.log(`  ${label}: old frame differs by ${dOld.toFixed(2)}, warped by ${dWarp.toFixed(2)} grey levels`);
    }
    // The drawing buffer: half the view's size per axis while the frame shown is an interactive one
    // of at most half its size, the view's own size for every other frame and after the release.
    const n = await page.evaluate(() => window.__raypc.shownLog.length);
    await drag(page, 120, 30, { steps: 24 });
    await waitConverged(page);
    const shown = await page.evaluate((k) => window.__raypc.shownLog.slice(k), n);
    const half = (s) => (s.interactive || s.playback) && 2 * s.width <= s.full[0] + 1 && 2 * s.height <= s.full[1] + 1;
    for (const s of shown) {
      const want = half(s) ? s.full.map((v) => Math.ceil(v / 2)) : s.full;
      check(s.buffer[0] === want[0] && s.buffer[1] === want[1],
        `frame of state ${s.id} (${s.width}x${s.height}${s.interactive ? ', interactive' : ''}) drawn into a ${s.buffer.join('x')} buffer, expected ${want.join('x')} for a ${s.full.join('x')} view`);
    }
    const last = shown.at(-1), canvas = await page.evaluate(() => { const c = document.getElementById('view3d'); return [c.width, c.height]; });
    check(!!last && !last.interactive && canvas[0] === last.full[0] && canvas[1] === last.full[1],
      `after the drag the still frame is drawn into ${canvas.join('x')}, the view is ${last?.full.join('x')}`);
    console.log(`  drag: ${shown.length} frames shown, ${shown.filter(half).length} of them into a half-size buffer; the still frame into ${canvas.join('x')}`);
  },

  // Stereo: choosing the anaglyph puts it in the state; the frame shown is the server's
  // anaglyph of two eyes (its header says so, at the state's size) and differs from the mono
  // picture; while a new frame is pending after an orbit, each eye is re-projected (the warped view
  // is much closer to the new frame than the old frame is); headless chromium has no headset, and
  // the UI says that WebXR immersive-vr is not there.
  async stereo({ context, url }) {
    const page = await openUi(context, url);
    await reprojectOn(page);
    await standardView(page);
    await volumeOnly(page);
    await waitConverged(page);
    const mono = await viewPixels(page);
    check((await rState(page)).stereo.mode === 'off', 'stereo is not off by default');
    await page.selectOption('#stereoMode', 'anaglyph');
    await waitConverged(page);
    const s = await rState(page);
    check(s.stereo.mode === 'anaglyph' && s.stereo.eyeSeparationKm > 0, `state.stereo after choosing anaglyph: ${JSON.stringify(s.stereo)}`);
    const h = await page.evaluate(() => window.__raypc.headers.at(-1));
    check(h.stereo && h.stereo.mode === 'anaglyph' && h.width === s.image.width && h.height === s.image.height &&
      h.stereo.eyeWidth === s.image.width && h.depthWidth === 2 * Math.ceil(s.image.width / 4),
    `frame header of the anaglyph state: ${JSON.stringify({ ...h, stats: undefined })}`);
    const anaglyph = await viewPixels(page);
    const dMono = meanAbsDiff(mono, anaglyph);
    check(dMono > 1, `the anaglyph hardly differs from the mono picture (${dMono.toFixed(2)} grey levels)`);
    console.log(`  anaglyph differs from mono by ${dMono.toFixed(2)} grey levels`);

    await page.evaluate(() => { window.__raypc.holdFrames = true; });
    const before = await page.evaluate(() => window.__raypc.warpedWhileWaiting);
    await drag(page, 45, 20);
    await page.evaluate(frames);
    const warped = await viewPixels(page);
    const during = await page.evaluate(() => ({ warped: window.__raypc.warpedWhileWaiting, shown: window.__raypc.lastShownId, sent: window.__raypc.lastSentId }));
    check(during.warped > before && during.sent > during.shown, `no warped stereo draw while the new frame was pending: ${JSON.stringify(during)}`);
    await page.evaluate(() => window.__raypc.releaseFrames());
    await waitConverged(page);
    const fresh = await viewPixels(page);
    const dOld = meanAbsDiff(anaglyph, fresh), dWarp = meanAbsDiff(warped, fresh);
    check(dOld > 1.5 && dWarp < 0.5 * dOld, `orbit in anaglyph: the warped view differs from the new frame by ${dWarp.toFixed(2)}, the old frame by ${dOld.toFixed(2)}`);
    console.log(`  orbit in anaglyph: old frame differs by ${dOld.toFixed(2)}, warped by ${dWarp.toFixed(2)} grey levels`);

    await page.waitForFunction(() => !/checking/.test(document.getElementById('enterVr').textContent));
    const xr = await page.textContent('#enterVr');
    const offered = await page.evaluate(async () => Boolean(await navigator.xr?.isSessionSupported('immersive-vr').catch(() => false)));
    check(!offered && xr === 'WebXR immersive VR is not available in this browser' || offered && xr === 'Enter VR', `WebXR control '${xr}' (immersive-vr offered: ${offered})`);
    console.log(`  ${xr}`);

    await page.selectOption('#stereoMode', 'off');
    await waitConverged(page);
    const off = await page.evaluate(() => window.__raypc.headers.at(-1));
    check((await rState(page)).stereo.mode === 'off' && !off.stereo, 'stereo off did not give a mono frame');
  },

  // WebXR immersive-vr with a mock headset: headless chromium has none, so an
  // init script (xrMock below) installs a fake navigator.xr whose session's animation frames the test
  // drives, with two eyes 0.2 m apart and mirrored asymmetric frusta, drawing into the halves of the
  // canvas. Only the core is shown (flat white), so each eye's picture is a disc whose limb tangents
  // are known. Checks: the control says "Enter VR"; entering sends side-by-side states whose
  // camera.views are the mock's poses mapped onto the planet (origin at the orbit eye, 1 m =
  // 10 000 km); the eyes' discs sit where the analytic limb tangents say (crossed parallax: right
  // of the frustum centre in the left eye, left of it in the right eye); turning the head moves the
  // drawn discs before any new frame arrives (warping); ending restores the desktop view. Without
  // navigator.xr the control says WebXR immersive VR is not available.
  async xr({ context, url }) {
    await context.addInitScript(xrMock);
    const page = await openUi(context, `${url}?xrmock=1`);
    await page.evaluate(() => {
      const s = window.__raypc.state();
      window.__raypc.setState({ ...s, image: { width: 384, height: 384 }, camera: { ...s.camera, distanceKm: 16000 },
        color: { ...s.color, opacity: [[0, 0], [1, 0]] }, background: [0, 0, 0],
        core: { ...s.core, visible: true, variable: '', color: [1, 1, 1] },
        shading: { ...s.shading, enabled: false, ambient: 1, diffuse: 0, specular: 0, shadows: false },
        pathlines: { ...s.pathlines, visible: false },
        reference: { ...s.reference, shells: { ...s.reference.shells, visible: false }, graticule: { ...s.reference.graticule, visible: false }, coastlines: { ...s.reference.coastlines, visible: false } } });
    });
    await waitConverged(page);
    const desktop = await viewPixels(page);
    const desktopState = await rState(page);
    await page.waitForFunction(() => !/checking/.test(document.getElementById('enterVr').textContent));
    const label = await page.textContent('#enterVr');
    check(label === 'Enter VR' && !(await page.isDisabled('#enterVr')), `with a headset the control says '${label}'`);

    await page.click('#enterVr');
    await page.waitForFunction(() => window.__xrMock.callbacks.length > 0 && document.getElementById('enterVr').textContent === 'Exit VR', null, { timeout: 10000 })
      .catch(async () => { throw new TestFailure(`the session did not start: ${JSON.stringify(await page.evaluate(() => window.__raypc.errors))}`); });
    // Drive the session's animation frames until the frame of the newest state (the head at rest:
    // a still state after the first interactive one) is converged and on screen.
    const settle = () => page.evaluate(async () => {
      const r = window.__raypc;
      for (let i = 0; i < 600; i++) {
        window.__xrMock.tick();
        const h = r.headers.at(-1);
        if (h && h.camera.views.length === 2 && !h.interactive && h.converged && h.id === r.lastSentId && r.lastShownId === h.id) {
          window.__xrMock.tick();
          return true;
        }
        await new Promise((res) => setTimeout(res, 50));
      }
      return false;
    });
    check(await settle(), 'no converged frame of the XR state arrived');
    const sent = await page.evaluate(() => window.__raypc.sentLog.at(-1));
    const header = await page.evaluate(() => window.__raypc.headers.at(-1));
    check(sent.stereoMode === 'side-by-side' && header.stereo?.mode === 'side-by-side', `XR states are side-by-side pairs: ${sent.stereoMode}, header ${JSON.stringify(header.stereo)}`);
    // The mock's eyes on the planet: the orbit eye is the origin, the camera's right/up/back its axes.
    const c = desktopState.camera, az = (c.azimuthDeg * Math.PI) / 180, el = (c.elevationDeg * Math.PI) / 180;
    const back = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
    const eyeKm = back.map((b, k) => c.targetKm[k] + b * c.distanceKm);
    const forward = back.map((b) => -b);
    const rightAxis = [forward[1], -forward[0], 0].map((x, _, a) => x / Math.hypot(...a));
    const mock = await page.evaluate(() => ({ ipd: window.__xrMock.ipd, frusta: window.__xrMock.frusta }));
    ['left', 'right'].forEach((eye, e) => {
      const v = sent.camera.views[e];
      const expected = eyeKm.map((p, k) => p + rightAxis[k] * (e === 0 ? -0.5 : 0.5) * mock.ipd * 10000);
      const dist = Math.hypot(...v.positionKm.map((p, k) => p - expected[k]));
      check(dist < 0.5, `${eye} eye at ${JSON.stringify(v.positionKm)}, expected ${JSON.stringify(expected)} (${dist.toFixed(3)} km off)`);
      const f = rotate(v.orientation, [0, 0, -1]);
      check(Math.hypot(...f.map((x, k) => x - forward[k])) < 1e-5, `${eye} eye looks along ${JSON.stringify(f)}, expected ${JSON.stringify(forward)}`);
      check(v.frustum.every((t, k) => Math.abs(t - mock.frusta[eye][k]) < 1e-5), `${eye} frustum ${JSON.stringify(v.frustum)}, the mock's ${JSON.stringify(mock.frusta[eye])}`);
      // The server keeps float32: the header's view is the one sent, rounded.
      const hv = header.camera.views[e], near = (a, b, tol) => a.every((x, k) => Math.abs(x - b[k]) <= tol);
      check(near(hv.positionKm, v.positionKm, 0.01) && near(hv.orientation, v.orientation, 1e-6) && near(hv.frustum, v.frustum, 1e-6),
        `the frame's ${eye} view ${JSON.stringify(hv)} is not the one sent ${JSON.stringify(v)}`);
    });

    // Each eye's disc: the middle row's lit extent in tangent units against the limb tangents
    // tan(θ ∓ α) of the core (θ: the centre's angle from the eye's view axis, α its angular radius).
    const radius = await page.evaluate(() => window.__raypc.info.coordinates.find((k) => k.name === 'radius'));
    const coreKm = radius.min, D = c.distanceKm; // the core sphere is the grid's inner radius
    // In the head's starting frame (metres × 10 000 km, +x right, -z forward) the centre is at
    // (0, 0, -D); an eye at k (∓ipd/2) along the turned head's +x (cos a, 0, -sin a) looks along
    // (-sin a, 0, -cos a).
    const predicted = (eye, yawDeg) => {
      const a = (yawDeg * Math.PI) / 180, k = (eye === 'left' ? -0.5 : 0.5) * mock.ipd * 10000;
      const v = [-k * Math.cos(a), 0, -D + k * Math.sin(a)];
      const theta = Math.atan2(v[0] * Math.cos(a) - v[2] * Math.sin(a), -v[0] * Math.sin(a) - v[2] * Math.cos(a));
      const alpha = Math.asin(coreKm / Math.hypot(...v));
      return [Math.tan(theta - alpha), Math.tan(theta + alpha)];
    };
    const discs = async () => page.evaluate((frusta) => {
      const src = document.getElementById('view3d');
      const w = src.width, h = src.height, half = Math.floor(w / 2);
      const cv = document.createElement('canvas');
      cv.width = w; cv.height = 1;
      const ctx = cv.getContext('2d', { willReadFrequently: true });
      ctx.drawImage(src, 0, Math.floor(h / 2), w, 1, 0, 0, w, 1);
      const d = ctx.getImageData(0, 0, w, 1).data;
      return ['left', 'right'].map((eye, e) => {
        let lo = -1, hi = -1;
        for (let i = 0; i < half; i++) {
          const g = (d[(e * half + i) * 4] + d[(e * half + i) * 4 + 1] + d[(e * half + i) * 4 + 2]) / 3;
          if (g > 128) { if (lo < 0) lo = i; hi = i + 1; }
        }
        const [l, r] = frusta[eye], t = (px) => l + (px / half) * (r - l);
        return { eye, lit: lo >= 0, left: t(lo), right: t(hi), pxPerTangent: half / (r - l) };
      });
    }, mock.frusta);
    const checkDiscs = (measured, yawDeg, what) => {
      for (const m of measured) {
        const [pl, pr] = predicted(m.eye, yawDeg), tol = 3 / m.pxPerTangent;
        check(m.lit && Math.abs(m.left - pl) < tol && Math.abs(m.right - pr) < tol,
          `${what}: the ${m.eye} eye's disc spans tangents [${m.left.toFixed(4)}, ${m.right.toFixed(4)}], expected [${pl.toFixed(4)}, ${pr.toFixed(4)}] ± ${tol.toFixed(4)}`);
      }
      const [l, r] = measured.map((m) => (m.left + m.right) / 2);
      console.log(`  ${what}: disc centres at tangents ${l.toFixed(4)} (left eye), ${r.toFixed(4)} (right eye)`);
      return [l, r];
    };
    const [cl, cr] = checkDiscs(await discs(), 0, 'XR frame');
    check(cl > 0.03 && cr < -0.03, `parallax: the core should lie right of the view axis in the left eye and left of it in the right eye (${cl}, ${cr})`);

    // Turning the head 6° to the left while the server's frames are held: the discs move right at
    // the next animation frame, drawn from the old frame.
    const before = await page.evaluate(() => ({ shown: window.__raypc.lastShownId, sent: window.__raypc.lastSentId }));
    await page.evaluate(() => { window.__raypc.holdFrames = true; window.__xrMock.head.yawDeg = 6; window.__xrMock.tick(); });
    const turned = await page.evaluate(() => ({ shown: window.__raypc.lastShownId, sent: window.__raypc.lastSentId, view: window.__raypc.sentLog.at(-1).camera.views[0] }));
    check(turned.shown === before.shown && turned.sent > before.sent, `the turned head should send a new state and show no new frame yet: ${JSON.stringify({ before, turned: { ...turned, view: undefined } })}`);
    const warpedDiscs = checkDiscs(await discs(), 6, 'head turned 6°, warped');
    check(warpedDiscs[0] > cl + 0.05, 'the warped discs did not move with the head');
    const warped = await viewPixels(page);
    await page.evaluate(() => window.__raypc.releaseFrames());
    check(await settle(), 'no converged frame after turning the head');
    checkDiscs(await discs(), 6, 'head turned 6°, new frame');
    const fresh = await viewPixels(page);
    console.log(`  warped vs new frame: ${meanAbsDiff(warped, fresh).toFixed(2)} grey levels`);

    await page.click('#enterVr');
    await page.waitForFunction(() => window.__xrMock.ended && document.getElementById('enterVr').textContent === 'Enter VR');
    await waitConverged(page);
    const after = await page.evaluate(() => ({ header: window.__raypc.headers.at(-1), state: window.__raypc.state() }));
    check(after.header.camera.views.length === 0 && !after.header.stereo && after.header.width === 384,
      `after the session the desktop frame should be mono 384 wide without views: ${JSON.stringify({ ...after.header, stats: undefined })}`);
    const restored = await viewPixels(page);
    const dRestored = meanAbsDiff(desktop, restored);
    check(dRestored < 0.5 && JSON.stringify(after.state.camera) === JSON.stringify(desktopState.camera), `the desktop view after VR differs by ${dRestored.toFixed(2)} grey levels`);
    console.log(`  desktop view restored (differs by ${dRestored.toFixed(2)} grey levels)`);

    const plain = await openUi(context, `${url}?noxr=1`);
    await plain.waitForFunction(() => !/checking/.test(document.getElementById('enterVr').textContent));
    const none = await plain.textContent('#enterVr');
    check(none === 'WebXR immersive VR is not available in this browser' && await plain.isDisabled('#enterVr'), `without navigator.xr the control says '${none}'`);
    console.log(`  without navigator.xr: '${none}' (disabled)`);
  },

  // Lighting: the light's controls are off while Lighting is not ticked; dragging the azimuth and
  // elevation sliders puts the unit vector of those angles (camera frame: x right, y up, z towards
  // the viewer) into state.shading.light, the specular slider into shading.specular, and each
  // changes the picture.
  async light({ context, url }) {
    const page = await openUi(context, url);
    await standardView(page);
    // The server's default state is lit: off first, then on again.
    await page.uncheck('#lighting');
    await waitConverged(page);
    check(await page.isDisabled('#lightAzimuth') && await page.isDisabled('#lightSpecular'), 'the light controls are enabled while lighting is off');
    await page.check('#lighting');
    await waitConverged(page);
    check(!(await page.isDisabled('#lightAzimuth')), 'the light controls stay disabled with lighting on');
    const s0 = await rState(page);
    check(s0.shading.enabled === true, `state.shading after ticking Lighting: ${JSON.stringify(s0.shading)}`);
    const lit = await viewPixels(page);
    // A click on a range input moves it there: azimuth near -90° (light from the left), elevation
    // near -35° (from below).
    const clickAt = async (id, fraction) => {
      const r = await page.locator(id).boundingBox();
      await page.mouse.click(r.x + r.width * fraction, r.y + r.height / 2);
      await waitConverged(page);
      return Number(await page.inputValue(id));
    };
    const az = await clickAt('#lightAzimuth', 0.25);
    const el = await clickAt('#lightElevation', 0.3);
    check(az < -45 && az > -135 && el < -15 && el > -75, `sliders after the clicks: azimuth ${az}, elevation ${el}`);
    const s1 = await rState(page);
    const rad = Math.PI / 180;
    const want = [Math.cos(el * rad) * Math.sin(az * rad), Math.sin(el * rad), Math.cos(el * rad) * Math.cos(az * rad)];
    check(s1.shading.light.every((v, i) => Math.abs(v - want[i]) < 1e-4), `state.shading.light ${JSON.stringify(s1.shading.light)} for azimuth ${az}°, elevation ${el}°: expected ${JSON.stringify(want)}`);
    const h = await page.evaluate(() => { const r = window.__raypc; return r.headers.at(-1).id === r.lastSentId; });
    check(h, 'the frame shown is not of the state with the new light');
    const moved = await viewPixels(page);
    const dLight = meanAbsDiff(lit, moved);
    check(dLight > 1, `moving the light to the left and below hardly changed the picture (${dLight.toFixed(2)} grey levels)`);
    const spec0 = s1.shading.specular;
    const spec = await clickAt('#lightSpecular', 0.97);
    const s2 = await rState(page);
    check(spec > 0.9 && s2.shading.specular === spec && spec0 !== spec, `shading.specular ${s2.shading.specular} after the slider went to ${spec} (was ${spec0})`);
    // A saved state's light comes back into the sliders.
    await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, shading: { ...s.shading, light: [0, 1, 0] } }); });
    await waitConverged(page);
    const back = [Number(await page.inputValue('#lightAzimuth')), Number(await page.inputValue('#lightElevation'))];
    check(back[1] === 90, `a state with the light straight up shows elevation ${back[1]}`);
    await page.uncheck('#lighting');
    await waitConverged(page);
    check(await page.isDisabled('#lightElevation'), 'the light controls stay enabled after lighting is turned off');
    // Shadows (shading.shadows): the light's direction casts them, so it is live again with
    // Shadows alone; the strength slider only with Shadows; the picture darkens.
    check(await page.isDisabled('#shadowStrength'), 'the shadow strength is enabled while Shadows is off');
    await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, shading: { ...s.shading, enabled: true, light: [-0.9, 0.4, 0.3] } }); });
    await waitConverged(page);
    const unshadowed = await viewPixels(page);
    await page.check('#shadows');
    await waitConverged(page);
    const s3 = await rState(page);
    check(s3.shading.shadows === true, `state.shading after ticking Shadows: ${JSON.stringify(s3.shading)}`);
    check(!(await page.isDisabled('#shadowStrength')), 'the shadow strength stays disabled with Shadows on');
    const shadowed = await viewPixels(page);
    const dShadow = meanAbsDiff(unshadowed, shadowed);
    check(dShadow > 0.5, `ticking Shadows hardly changed the picture (${dShadow.toFixed(2)} grey levels)`);
    const strength = await clickAt('#shadowStrength', 0.1);
    const s4 = await rState(page);
    check(strength < 0.3 && s4.shading.shadowStrength === strength, `shading.shadowStrength ${s4.shading.shadowStrength} after the slider went to ${strength}`);
    await page.uncheck('#lighting');
    await waitConverged(page);
    check(!(await page.isDisabled('#lightAzimuth')) && await page.isDisabled('#lightSpecular'), 'with Shadows alone the light direction must be live and the highlight not');
    console.log(`  light at azimuth ${az}°, elevation ${el}°: picture changed by ${dLight.toFixed(2)} grey levels; specular ${spec0} -> ${spec}; shadows changed it by ${dShadow.toFixed(2)}`);
  },

  // The persistence diagram: it shows the pairs of the step shown and the stored seeds' threshold;
  // dragging its threshold handle up (between the two most persistent pairs) sets a "seed
  // persistence" range in state.pathlines.filters, and the lines shown are exactly those of the
  // window whose seed persistence (from GET /api/pathlines) passes it: fewer, and the picture
  // changes. Dragging it down to the stored threshold removes the filter.
  async persistence({ context, url }) {
    const ds = await info(url);
    const last = ds.steps.length - 1;
    const page = await openUi(context, url);
    await standardView(page);
    // With the pathlines hidden, stepping through time asks for no diagrams.
    let diagrams = 0;
    page.on('request', (r) => { if (r.url().includes('api/persistence')) diagrams++; });
    for (const step of [1, 2, 3].filter((k) => k <= last)) {
      await page.evaluate((n) => window.__raypc.setState({ ...window.__raypc.state(), step: n }), step);
      await waitConverged(page);
    }
    check(diagrams === 0, `${diagrams} persistence diagrams asked for while the pathlines were hidden`);
    await page.evaluate((n) => {
      const s = window.__raypc.state();
      window.__raypc.setState({ ...s, step: n, core: { ...s.core, visible: false }, color: { ...s.color, opacity: [[0, 0], [1, 0]] },
        pathlines: { ...s.pathlines, visible: true, radiusKm: 250, minWidthPx: 0 } });
    }, last);
    await waitConverged(page);
    await page.waitForFunction((n) => window.__raypc.pathlines?.lines > 0 && window.__raypc.persistence?.step === n, last, { timeout: 20000 })
      .catch(() => { throw new TestFailure('no pathlines or no persistence diagram of the last step arrived'); });
    const d = await page.evaluate(() => window.__raypc.persistence);
    check(d.stored && d.stored.seedPersistenceColumn && d.stored.rule === 'persistence' && d.pairs.length >= 3,
      `diagram of step ${last}: ${JSON.stringify({ ...d, pairs: d.pairs.length })}`);
    const circles = await page.locator('#persistencePlot circle.pair').count();
    check(circles >= 3, `${circles} pairs drawn`);
    const before = await viewPixels(page);
    const pl0 = await page.evaluate(() => window.__raypc.pathlines);
    check(pl0.visibleLines === pl0.lines, `without filters ${pl0.visibleLines} of ${pl0.lines} lines counted`);

    // The handle to half way (on the log scale) between the two most persistent pairs (the plot is
    // at the bottom of the side panel: scrolled into view first).
    await page.locator('#persistencePlot').scrollIntoViewIfNeeded();
    const ys = await page.evaluate(() => [...document.querySelectorAll('#persistencePlot circle.pair')]
      .map((c) => { const r = c.getBoundingClientRect(); return { y: r.y + r.height / 2, p: c.__data__.persistence }; })
      .sort((a, b) => b.p - a.p));
    const handle = await page.locator('#persistenceHandle line').boundingBox();
    const hx = handle.x + handle.width / 2, hy = handle.y + handle.height / 2;
    const ty = (ys[0].y + ys[1].y) / 2;
    await page.mouse.move(hx, hy);
    await page.mouse.down();
    for (let i = 1; i <= 8; i++) await page.mouse.move(hx, hy + ((ty - hy) * i) / 8);
    await page.mouse.up();
    await waitConverged(page);
    const s1 = await rState(page);
    const f = s1.pathlines.filters.filter((x) => x.name === 'seed persistence');
    check(f.length === 1 && f[0].min > ys[1].p && f[0].min < ys[0].p && f[0].max >= ys[0].p,
      `the filter after the drag ${JSON.stringify(s1.pathlines.filters)}; the two top pairs ${ys[0].p}, ${ys[1].p}`);
    // Which lines pass, from the attributes the server stores.
    const r = await fetch(`${url}api/pathlines?step=${last}&window=${s1.pathlines.window}`);
    const buf = Buffer.from(await r.arrayBuffer());
    const { header, bodyOffset } = binaryHeader(buf);
    const k = header.columns.indexOf('seed persistence');
    check(k >= 0, `no seed persistence column: ${header.columns.join(', ')}`);
    const values = new Float32Array(buf.buffer.slice(buf.byteOffset + bodyOffset, buf.byteOffset + buf.length));
    let passing = 0;
    for (let i = 0; i < header.lines; i++) { const v = values[i * header.columns.length + k]; if (v >= f[0].min && v <= f[0].max) passing++; }
    const pl1 = await page.evaluate(() => window.__raypc.pathlines);
    check(pl1.visibleLines === passing && passing > 0 && passing < pl0.lines,
      `visible lines ${pl0.lines} -> ${pl1.visibleLines}; ${passing} lines have a seed persistence of at least ${f[0].min}`);
    const h = await page.evaluate(() => { const r = window.__raypc, h = r.headers.at(-1); return h.id === r.lastSentId ? h : null; });
    check(h && h.pathlines && h.pathlines.visible === passing, `the server shows ${JSON.stringify(h?.pathlines)} lines, expected ${passing}`);
    const kept = await page.locator('#persistencePlot circle.kept').count();
    check(kept === 1, `${kept} pairs highlighted above the threshold, expected the global pair alone`);
    const after = await viewPixels(page);
    const dF = meanAbsDiff(before, after);
    check(dF > 0.1, `the threshold hardly changed the picture (${dF.toFixed(2)})`);
    console.log(`  threshold ${f[0].min.toFixed(1)} (pairs ${ys[0].p.toFixed(1)}, ${ys[1].p.toFixed(1)}; stored above ${d.stored.threshold.toFixed(1)}): lines ${pl0.lines} -> ${passing}, picture changed by ${dF.toFixed(2)}`);

    // Back down to the bottom of the plot: below the stored threshold, so no filter at all.
    const h2 = await page.locator('#persistenceHandle line').boundingBox();
    const plot = await page.locator('#persistencePlot').boundingBox();
    await page.mouse.move(h2.x + h2.width / 2, h2.y + h2.height / 2);
    await page.mouse.down();
    for (let i = 1; i <= 8; i++) await page.mouse.move(h2.x + h2.width / 2, h2.y + ((plot.y + plot.height - h2.y) * i) / 8);
    await page.mouse.up();
    await waitConverged(page);
    const s2 = await rState(page);
    const pl2 = await page.evaluate(() => window.__raypc.pathlines);
    check(!s2.pathlines.filters.some((x) => x.name === 'seed persistence') && pl2.visibleLines === pl0.lines,
      `after dragging the handle down: filters ${JSON.stringify(s2.pathlines.filters)}, ${pl2.visibleLines} of ${pl0.lines} lines`);
  },

  // Play runs over all steps in order, sends the next step only after a frame of the current one
  // arrived, keeps the colour range, and pausing leaves a converged frame of the current step.
  // Each step is rendered while the one before it shows: its frame is shown a
  // period after it was sent, at the state's full size.
  async play({ context, url, gpu }) {
    const page = await openUi(context, url);
    const ds = await info(url);
    const nSteps = ds.steps.length;
    check(nSteps >= 3, `fixture has ${nSteps} steps`);
    const rangeBefore = await page.evaluate(() => [document.getElementById('rangeMin').value, document.getElementById('rangeMax').value]);
    await page.selectOption('#fps', '2');
    const rows = await page.evaluate(() => window.__raypc.parcoords.rowCount);
    const firstSampleStep = await page.evaluate(() => window.__raypc.sampleStep);
    check(rows === 20000, `the sample has ${rows} rows, the case asked for 20000`);
    const sampleUrls = [];
    page.on('request', (r) => { if (r.url().includes('/api/sample')) sampleUrls.push(r.url()); });
    const t0 = await page.evaluate(() => performance.now());
    await page.click('#play');
    // While playing, each new step's sample is drawn coarsely: a quarter of its 20 000 lines.
    let playingLines = 0;
    await page.waitForFunction((n) => {
      const steps = window.__raypc.sentLog.filter((e) => e.playback).map((e) => e.step);
      return steps.length >= n + 2;
    }, nSteps, { timeout: 40000 }).catch(() => { throw new TestFailure('playback did not advance through every step within 40 s'); });
    // (the sample of a later step has been loaded meanwhile: it loads at most once a second)
    await page.waitForFunction((first) => window.__raypc.sampleStep !== first, firstSampleStep, { timeout: 20000 })
      .catch(() => { throw new TestFailure('no other step\'s sample was loaded while playing'); });
    // A new step's sample is fetched by the sample worker (off the page's main thread), its
    // variables only: the rows' coordinates are the same in every step.
    check(page.workers().some((w) => w.url().endsWith('/sample_worker.js')), `no sample worker among ${page.workers().map((w) => w.url()).join(', ') || 'no workers'}`);
    check(sampleUrls.length > 0 && sampleUrls.every((u) => u.includes('columns=variables')),
      `samples fetched while playing: ${sampleUrls.join(', ') || 'none seen'}; expected each with columns=variables`);
    playingLines = await page.evaluate(() => window.__raypc.parcoords.timing.lines.foreground);
    check(playingLines === 5000, `while playing, the parallel coordinates drew ${playingLines} of ${rows} lines, expected 5000 (coarse)`);
    await page.click('#play');
    await waitConverged(page);
    // Paused: every line again, of the step paused at (its sample's values, taken into the same rows).
    await page.waitForFunction(() => window.__raypc.sampleStep === window.__raypc.state().step, null, { timeout: 20000 })
      .catch(() => { throw new TestFailure('after pausing, the sample of the step shown was not loaded'); });
    const paused = await page.evaluate(async () => {
      const r = window.__raypc;
      const names = r.info.sample.columns;
      const values = new Float32Array(await (await fetch(`api/sample?step=${r.state().step}`)).arrayBuffer());
      const rows = r.parcoords.rows;
      let mismatches = 0;
      for (const i of [0, 1, 777, rows.length - 1])
        names.forEach((name, k) => { if (rows[i][name] !== values[i * names.length + k]) mismatches++; });
      return { lines: r.parcoords.timing.lines.foreground, mismatches };
    });
    check(paused.lines === rows, `after pausing, ${paused.lines} of ${rows} lines drawn, expected all`);
    check(paused.mismatches === 0, `after pausing, ${paused.mismatches} values of the lines differ from the step's sample`);
    const log = await page.evaluate((since) => ({
      sent: window.__raypc.sentLog.filter((e) => e.t >= since),
      frames: window.__raypc.frameLog.filter((e) => e.t >= since),
      shown: window.__raypc.shownLog.filter((e) => e.t >= since && e.playback),
      image: window.__raypc.state().image,
      step: window.__raypc.state().step,
      last: window.__raypc.headers[window.__raypc.headers.length - 1],
    }), t0);
    const playSent = log.sent.filter((e) => e.playback);
    for (let i = 1; i < playSent.length; i++) {
      const prev = playSent[i - 1], cur = playSent[i];
      check(cur.step === (prev.step + 1) % nSteps, `playback went from step ${prev.step} to ${cur.step}`);
      const answered = log.frames.some((f) => f.id === prev.id && f.t <= cur.t);
      check(answered, `step ${cur.step} (state ${cur.id}) was sent before any frame of step ${prev.step} (state ${prev.id}) arrived`);
    }
    // Shown three quarters of a period or more (375 ms at 2 steps/s) after it was sent: the server
    // had that time for it (playback.ts keeps it even when a step came late). Each step is either
    // at the size asked and level 0 (a level-0 pass of this small grid fits half a second many
    // times over on an idle machine) or refined by several passes at the level the server's
    // measured throughput chose (under load, e.g. a full ctest run: CI once saw level 2 at half
    // size, 8 passes), or one pass the server cut short (converged after 1 of its passes) to leave
    // the cores to rendering the next steps ahead. A frame rendered ahead (cached) is no coarser
    // than the finest level of the frames the steps of playback rendered themselves before it (CI
    // once showed a draft at level 1, guessed before the first step, where the steps made level 0).
    // At least one step is at the size and level asked.
    check(log.shown.length >= nSteps, `${log.shown.length} frames of playback shown, expected one a step at least`);
    let full = 0, cutShort = 0, ahead = 0, finestRendered = Infinity;
    for (const s of log.shown) {
      const sent = playSent.find((e) => e.id === s.id);
      check(sent && s.t - sent.t >= 370, `step ${s.step} (state ${s.id}) was shown ${sent ? (s.t - sent.t).toFixed(0) : '?'} ms after it was sent, expected 375 ms or more`);
      const asked = s.level === 0 && s.width === log.image.width && s.height === log.image.height;
      const cut = s.pass === 1 && s.converged && s.passes > 1;
      full += asked ? 1 : 0;
      cutShort += cut && !asked ? 1 : 0;
      check(asked || s.pass > 1 || cut,
        `step ${s.step} was shown at ${s.width}x${s.height} (level ${s.level}) after ${s.pass} of ${s.passes} passes: neither the size and level asked (${log.image.width}x${log.image.height}, 0) nor refined nor cut short`);
      if (s.cached) {
        ahead++;
        check(s.level <= finestRendered, `step ${s.step} was shown from a frame rendered ahead at level ${s.level}, coarser than the level ${finestRendered} the steps of playback rendered before it`);
      } else {
        finestRendered = Math.min(finestRendered, s.level);
      }
    }
    console.log(`  ${full} of ${log.shown.length} playback frames at the size asked and level 0, ${ahead} rendered ahead, ${cutShort} coarse ones cut short`);
    check(full >= 1, `no playback frame at the size asked (${log.image.width}x${log.image.height}) and level 0: ${JSON.stringify(log.shown.map((s) => [s.width, s.level, s.pass]))}`);
    const stepsSeen = new Set(log.frames.map((f) => f.step));
    check(stepsSeen.size === nSteps, `frames of steps ${[...stepsSeen].join(',')} arrived, expected all ${nSteps}`);
    check(log.last.step === log.step && log.last.converged, `after pausing, the last frame is ${JSON.stringify(log.last)} for step ${log.step}`);
    // "GPU stall due to ReadPixels" is Chrome's note that its software compositor
    // (--disable-gpu) reads the WebGL canvas back to show it (at most four times, then Chrome stops
    // repeating it); with GPU compositing (browser.gpu.play) nothing of the page reads pixels back.
    const stalls = page.raypcWarnings.filter((w) => w.includes('GPU stall due to ReadPixels'));
    console.log(`  "GPU stall due to ReadPixels" logged ${stalls.length} times (${gpu ? 'GPU' : 'software'} compositing)`);
    if (gpu) check(stalls.length === 0, `with GPU compositing the page logged ${stalls.length} ReadPixels stalls: ${stalls[0] ?? ''}`);
    const rangeAfter = await page.evaluate(() => [document.getElementById('rangeMin').value, document.getElementById('rangeMax').value]);
    check(JSON.stringify(rangeBefore) === JSON.stringify(rangeAfter), `the colour range changed during playback: ${rangeBefore} -> ${rangeAfter}`);
    const label = await page.textContent('#stepLabel');
    check(label.includes(`step ${log.step} of 0–${nSteps - 1}`) && label.includes('Myr'), `step label '${label}' (steps numbered from 0, as --time)`);

    // A page whose sample worker cannot start (its script not loaded) fetches the samples itself:
    // the first one whole, a new step's variables, the same values as the step's whole sample.
    await context.route('**/sample_worker.js', (r) => r.abort());
    try {
      const bare = await openUi(context, url);
      await bare.waitForFunction(() => window.__raypc.parcoords.rowCount > 0, null, { timeout: 20000 })
        .catch(() => { throw new TestFailure('without its worker, the page loaded no sample'); });
      await bare.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, step: 1 }); });
      await bare.waitForFunction(() => window.__raypc.sampleStep === 1, null, { timeout: 20000 })
        .catch(() => { throw new TestFailure('without its worker, the sample of step 1 was not loaded'); });
      const mismatches = await bare.evaluate(async () => {
        const r = window.__raypc, names = r.info.sample.columns, rows = r.parcoords.rows;
        const values = new Float32Array(await (await fetch('api/sample?step=1')).arrayBuffer());
        let n = 0;
        for (const i of [0, 5, rows.length - 1]) names.forEach((name, k) => { if (rows[i][name] !== values[i * names.length + k]) n++; });
        return n;
      });
      check(mismatches === 0, `without its worker, ${mismatches} values of step 1's lines differ from its sample`);
      check(bare.raypcErrors.every((e) => !e.includes('api/sample')), `page errors: ${bare.raypcErrors.join(' | ')}`);
      await bare.close();
    } finally {
      await context.unroute('**/sample_worker.js');
    }
  },

  // Save downloads the whole state (accepted by `raypc render --state`); reloading the page and
  // loading that file restores the same image; so does the shareable URL; the screenshot is a PNG
  // of the state's size; a bad file is refused with a message and changes nothing.
  async save_load({ context, url, tmp, raypc, dataset }) {
    const page = await openUi(context, url);
    await standardView(page);
    await page.selectOption('#variable', 'temperature');
    await page.selectOption('#colorMap', 'inferno');
    await drag(page, -60, 30);
    await brushAxis(page, 'depth', 0.1, 0.5);
    await waitConverged(page);
    const imageA = await viewPixels(page);
    const stateA = await rState(page);
    if (process.env.RAYPC_TEST_DEBUG) await page.locator('#view3d').screenshot({ path: join(process.env.RAYPC_TEST_DEBUG, 'saved.png') });
    check(stateA.color.variable === 'temperature' && stateA.color.colorMap === 'inferno' && stateA.brushes.length === 1,
      `UI changes did not reach the state: ${JSON.stringify(stateA.color)} ${JSON.stringify(stateA.brushes)}`);

    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#save')]);
    const file = join(tmp, 'STATE.json');
    await download.saveAs(file);
    const saved = JSON.parse(readFileSync(file, 'utf8'));
    check(JSON.stringify(saved) === JSON.stringify(stateA), 'the saved file is not the UI state');
    const cli = spawnSync(raypc, ['render', dataset, '--state', file, '-o', join(tmp, 'cli.png'), '--passes', '1'], { encoding: 'utf8', timeout: 60000 });
    check(cli.status === 0, `raypc render --state refused the saved state: ${cli.stderr}`);

    const hash = new URL(page.url()).hash;
    check(hash.startsWith('#state='), `the page URL holds no state: ${page.url()}`);

    await page.goto(url);
    await waitConverged(page);
    const imageDefault = await viewPixels(page);
    check(meanAbsDiff(imageA, imageDefault) > 2, 'the default view looks like the saved one; the test would prove nothing');
    const sentBefore = await page.evaluate(() => window.__raypc.lastSentId);
    await page.setInputFiles('#load', file);
    await page.waitForFunction((n) => window.__raypc.lastSentId > n, sentBefore, { timeout: 5000 })
      .catch(() => { throw new TestFailure('loading the saved file sent no state'); });
    await waitConverged(page);
    const imageB = await viewPixels(page);
    const stateB = await rState(page);
    check(JSON.stringify(stateB) === JSON.stringify(stateA), `loaded state differs: ${JSON.stringify(stateB)}`);
    const dB = meanAbsDiff(imageA, imageB);
    if (process.env.RAYPC_TEST_DEBUG) {
      await page.locator('#view3d').screenshot({ path: join(process.env.RAYPC_TEST_DEBUG, 'loaded.png') });
      console.log(JSON.stringify(await page.evaluate(() => window.__raypc.headers.slice(-3))), JSON.stringify(stateA));
    }
    check(dB < 1, `the loaded state renders differently (mean difference ${dB.toFixed(2)})`);
    const pcBrush = await page.evaluate(() => window.__raypc.parcoords.brushes());
    check(pcBrush.length === 1 && pcBrush[0].name === 'depth' && Math.abs(pcBrush[0].min - stateA.brushes[0].min) < 1e-3 * Math.abs(stateA.brushes[0].max - stateA.brushes[0].min) + 1e-6,
      `parallel coordinates show brushes ${JSON.stringify(pcBrush)} after loading ${JSON.stringify(stateA.brushes)}`);

    const page2 = await openUi(context, url, { hash });
    const stateC = await rState(page2);
    check(JSON.stringify(stateC) === JSON.stringify(stateA), 'the shared URL did not restore the state');
    const dC = meanAbsDiff(imageA, await viewPixels(page2));
    check(dC < 1, `the shared URL renders differently (mean difference ${dC.toFixed(2)})`);
    const pcBrush2 = await page2.evaluate(() => window.__raypc.parcoords.brushes());
    check(pcBrush2.length === 1 && pcBrush2[0].name === 'depth', `parallel coordinates opened from the URL show brushes ${JSON.stringify(pcBrush2)}`);

    const { width: w, height: h } = await screenshot(page, join(tmp, 'shot.png'));
    check(w === stateA.image.width && h === stateA.image.height, `screenshot is ${w}x${h}, the state's image ${stateA.image.width}x${stateA.image.height}`);

    const bad = join(tmp, 'bad.json');
    writeFileSync(bad, JSON.stringify({ ...stateA, version: 99 }));
    const errorsBefore = await page.evaluate(() => window.__raypc.errors.length);
    await page.setInputFiles('#load', bad);
    await page.waitForFunction((n) => window.__raypc.errors.length > n, errorsBefore, { timeout: 5000 })
      .catch(() => { throw new TestFailure('loading a state of version 99 showed no error'); });
    const msg = await page.textContent('#error');
    check(/version/.test(msg) && (await page.isVisible('#error')), `error shown for a bad state file: '${msg}'`);
    check(JSON.stringify(await rState(page)) === JSON.stringify(stateA), 'a refused state file changed the state');
  },

  // A selection with samples shows its lines in the parallel coordinates whatever
  // the brushed axis: a coordinate (depth, an inverted axis: 0 at the top), a stored variable and a
  // derived one. Counted as lines drawn and as painted pixels of the brushed layer beyond its veil.
  async brush_kinds({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const linePixels = () => page.evaluate(() => {
      const c = document.querySelector('#parcoords canvas.brushed');
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      const key = (i) => `${d[i]},${d[i + 1]},${d[i + 2]},${d[i + 3]}`;
      const counts = new Map();
      for (let i = 0; i < d.length; i += 4 * 13) counts.set(key(i), (counts.get(key(i)) ?? 0) + 1);
      const veil = [...counts].sort((a, b) => b[1] - a[1])[0][0];  // the most common value
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (key(i) !== veil) n++;
      return n;
    });
    for (const [kind, brushes] of [
      ['coordinate', [{ name: 'depth', min: 560, max: 760 }]],
      ['variable', [{ name: 'temperature anomaly', min: -10000, max: -25 }]],
      ['derived', [{ name: 'velocity magnitude', min: 0, max: 5 }]],
    ]) {
      await page.evaluate((b) => window.__raypc.setState({ ...window.__raypc.state(), brushes: b }), brushes);
      await waitConverged(page);
      await page.waitForFunction(() => window.__raypc.parcoords.timing.lines.brushed > 0, null, { timeout: 10000 })
        .catch(() => { throw new TestFailure(`${kind} brush ${JSON.stringify(brushes)}: no line drawn in the brushed layer`); });
      await page.waitForTimeout(500);
      const px = await linePixels();
      check(px > 1000, `${kind} brush ${JSON.stringify(brushes)}: ${px} painted pixels besides the veil`);
      console.log(`  ${kind}: ${await page.evaluate(() => window.__raypc.parcoords.timing.lines.brushed)} lines, ${px} pixels`);
    }
    // Item 12: tick labels and titles carry a dark halo over the lines.
    const halo = await page.evaluate(() => {
      const t = document.querySelector('#parcoords .tick text');
      const st = getComputedStyle(t);
      return { order: st.paintOrder, width: parseFloat(st.strokeWidth), stroke: st.stroke };
    });
    check(/^stroke/.test(halo.order) && halo.width >= 2 && halo.stroke !== 'none', `tick labels without a halo: ${JSON.stringify(halo)}`);
  },

  // Task 1's ranges brushed by hand from the default view turn "show the
  // selection" on, and the 3D view then shows the selected material (pixels brighter than the
  // background and the core, counted with the mode on and off); dragged ends land on their axis'
  // snap step (a tenth of the labelled tick step), a value typed in the Selection panel stays exact.
  async show_selection({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const ds = await info(url);
    check(!(await rState(page)).selection.show, 'the default view shows the selection before anything is brushed');
    const range = (name) => ds.variables.find((v) => v.name === name) ?? ds.coordinates.find((c) => c.name === name);
    // The fraction down the axis of a value: depth grows downwards, every other axis upwards.
    const down = (name, v) => { const r = range(name); const u = (v - r.min) / (r.max - r.min); return name === 'depth' ? u : 1 - u; };
    const clamp = (u) => Math.min(0.999, Math.max(0.001, u));
    const task1 = [['depth', 560, 760], ['radial velocity', -1e9, 0], ['temperature anomaly', -1e9, -25]];
    // The fixture's radial velocity may not straddle 0 (then its brush would select all or nothing):
    // brushed only where it does, as on the demo.
    const v = range('radial velocity');
    const brushed = task1.filter(([name]) => name !== 'radial velocity' || (v && v.min < 0 && v.max > 0));
    for (const [name, lo, hi] of brushed) {
      const from = clamp(down(name, name === 'depth' ? lo : hi)), to = clamp(down(name, name === 'depth' ? hi : lo));
      await brushAxis(page, name, from, to);
    }
    await waitConverged(page);
    await page.waitForFunction((n) => window.__raypc.selection && Number.isFinite(window.__raypc.selection.fractionOfMantle) && window.__raypc.state().brushes.length === n,
      brushed.length, { timeout: 10000 }).catch(async () => { throw new TestFailure(`no selection after brushing task 1 by hand: brushes ${JSON.stringify((await rState(page)).brushes)}, selection ${JSON.stringify(await page.evaluate(() => window.__raypc.selection))}`); });
    const s = await rState(page);
    const fraction = await page.evaluate(() => window.__raypc.selection.fractionOfMantle);
    console.log(`  brushed by hand: ${s.brushes.map((b) => `${b.name} ${b.min}…${b.max}`).join(', ')}; ${(100 * fraction).toFixed(2)} % selected`);
    check(fraction > 0, 'the hand-brushed task-1 selection is empty on the fixture: the test would be vacuous');
    check(s.selection.show, 'brushing from the default view did not turn "show the selection" on');
    check(await page.isChecked('#showSelection'), 'the "show the selection" box is not ticked');
    // Every dragged end on its axis' snap step (or at the axis' end, where the drag was clamped).
    for (const b of s.brushes) {
      const r = range(b.name);
      const step = await page.evaluate(([lo, hi]) => window.__raypc.snapStep({ name: '', units: '', min: lo, max: hi }), [r.min, r.max]);
      for (const v of [b.min, b.max]) {
        const k = v / step;
        check(Math.abs(k - Math.round(k)) < 1e-6, `${b.name}: brush end ${v} is not a multiple of the snap step ${step}`);
      }
    }
    const visible = () => page.evaluate(() => {
      // Full-resolution pixels brighter than the dark core and the background.
      const { data: d } = window.__viewImageData();
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (Math.max(d[i], d[i + 1], d[i + 2]) > 90) n++;
      return n;
    });
    const shown = await visible();
    await page.click('#showSelection');
    await waitConverged(page);
    check(!(await rState(page)).selection.show, 'unticking the box left the mode on');
    const hidden = await visible();
    console.log(`  bright pixels: ${shown} with the selection shown, ${hidden} without`);
    check(shown > 2 * hidden + 500, `the shown selection adds too little to the view: ${shown} bright pixels with it, ${hidden} without`);
    // Once turned off it stays off: clearing and brushing again does not turn it on.
    await page.click('#clearBrushes');
    await brushAxis(page, 'depth', clamp(down('depth', 560)), clamp(down('depth', 760)));
    await waitConverged(page);
    check(!(await rState(page)).selection.show, 'the mode came back on after the user turned it off');
    // A typed value stays exact.
    await page.fill('#selection input.brushMin', '557.6');
    await page.press('#selection input.brushMin', 'Enter');
    await waitConverged(page);
    const typed = (await rState(page)).brushes.find((b) => b.name === 'depth');
    check(typed.min === 557.6, `the typed depth minimum became ${typed.min}`);
  },

  // From 1366x768 to 2560x1440 the presets, the time bar and the 3D view are
  // visible without scrolling; at 1000x700 the transfer-function editor still is.
  async layout({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const boxes = () => page.evaluate(() => {
      const box = (sel) => { const b = document.querySelector(sel).getBoundingClientRect(); return { top: b.top, bottom: b.bottom, height: b.height }; };
      return { presets: box('#presets'), tf: box('#tf'), side: box('#side'), view: box('#view3d'), play: box('#play'),
        selection: box('#selection'), statsTime: box('#statsTime'),
        sideScroll: document.getElementById('side').scrollTop, pageScroll: document.documentElement.scrollHeight - window.innerHeight,
        error: document.getElementById('error').hidden ? '' : document.getElementById('error').textContent };
    });
    for (const [w, h] of [[1366, 768], [1920, 1080], [2560, 1440]]) {
      await page.setViewportSize({ width: w, height: h });
      await page.waitForTimeout(500);
      const b = await boxes();
      check(b.pageScroll <= 0 && b.sideScroll === 0, `${w}x${h}: the page or the side panel is scrolled (${b.pageScroll}, ${b.sideScroll})${b.error ? `; error shown: ${b.error}` : ''}`);
      check(b.presets.height > 40 && b.presets.top >= b.side.top && b.presets.bottom <= b.side.bottom,
        `${w}x${h}: the presets (${Math.round(b.presets.top)}-${Math.round(b.presets.bottom)} px) are not within the side panel's visible ${Math.round(b.side.top)}-${Math.round(b.side.bottom)} px`);
      check(b.play.bottom <= h && b.view.height >= 0.4 * h, `${w}x${h}: time bar at ${Math.round(b.play.bottom)} px, view ${Math.round(b.view.height)} px high`);
      // Issue 47: the selection's figure and its plot over time come before the colour and
      // rendering controls, above the fold.
      console.log(`  ${w}x${h}: side ${Math.round(b.side.top)}-${Math.round(b.side.bottom)}, selection ${Math.round(b.selection.top)}-${Math.round(b.selection.bottom)}, plot over time ${Math.round(b.statsTime.top)}-${Math.round(b.statsTime.bottom)}, tf ${Math.round(b.tf.top)}`);
      check(b.selection.bottom <= b.side.bottom && b.statsTime.bottom <= b.side.bottom && b.statsTime.top < b.tf.top,
        `${w}x${h}: the selection (${Math.round(b.selection.top)}-${Math.round(b.selection.bottom)} px) or its plot over time (${Math.round(b.statsTime.top)}-${Math.round(b.statsTime.bottom)} px) is below the side panel's visible ${Math.round(b.side.top)}-${Math.round(b.side.bottom)} px, or after the transfer function`);
    }
    await page.setViewportSize({ width: 1000, height: 700 });
    await page.waitForTimeout(500);
    const small = await boxes();
    check(small.tf.bottom <= small.side.bottom, `1000x700: the transfer-function editor ends at ${Math.round(small.tf.bottom)} px, below the side panel's ${Math.round(small.side.bottom)} px`);
  },

  // The map and the section (the bottom panel's tab): the pictures are the pane's size in
  // device pixels; the depth slider changes the map; the brushes grey what they leave out; the pointer
  // reads the value under it (the server's probe); two clicks on the map set the section's ends and
  // change the section; the map's settings live in the state (the URL) and come back on reload.
  async slices({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    // Cyan pixels of the 3D view: the marks of the map's depth and the section (map.showInView).
    const cyan = () => page.evaluate(() => {
      const { data: d } = window.__viewImageData();
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i + 2] > d[i] + 60 && d[i + 1] > d[i] + 60) n++;
      return n;
    });
    const cyanBefore = await cyan();
    await page.click('#pcTabSlices');
    await page.waitForFunction(() => window.__raypc.state().map.showInView === true, null, { timeout: 5000 })
      .catch(() => { throw new TestFailure('showing the tab did not set map.showInView'); });
    await waitConverged(page);
    const cyanShown = await cyan();
    console.log(`  cyan pixels in the 3D view: ${cyanBefore} before the tab, ${cyanShown} with it`);
    check(cyanShown > cyanBefore + 200, `the 3D view does not mark the map's depth and the section: ${cyanBefore} -> ${cyanShown} cyan pixels`);
    const shown = () => page.evaluate(() => ({ map: window.__raypc.slices.map.shown, section: window.__raypc.slices.section.shown }));
    const nextPicture = async (which, before) => page.waitForFunction(([w, b]) => window.__raypc.slices[w].shown > b
        && document.getElementById(w === 'map' ? 'mapImage' : 'sectionImage').complete, [which, before], { timeout: 20000 })
      .catch(async () => { throw new TestFailure(`no new ${which} picture (${JSON.stringify(await shown())}); errors: ${await page.evaluate(() => window.__raypc.errors.join('; '))}`); });
    await nextPicture('map', 0);
    await nextPicture('section', 0);
    // The spectrum of the map's depth (POST /api/spectrum): a plot of degrees 1..lmax, the same numbers
    // the server gives for that state, and a new one when the depth changes.
    const spectrumOf = () => page.evaluate(() => ({ ...document.getElementById('spectrumPlot').dataset,
      circles: document.querySelectorAll('#spectrumPlot circle').length, note: document.getElementById('spectrumNote').textContent }));
    await page.waitForFunction(() => Number(document.getElementById('spectrumPlot').dataset.points) > 0, null, { timeout: 20000 })
      .catch(async () => { throw new TestFailure(`no spectrum plot: ${JSON.stringify(await spectrumOf())}`); });
    const plotted = await spectrumOf();
    const asked = await (await fetch(`${url}api/spectrum`, { method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify(await rState(page)) })).json();
    console.log(`  spectrum plot: ${JSON.stringify(plotted)}; the server: lmax ${asked.lmax} at ${asked.depthKm} km`);
    check(Number(plotted.lmax) === asked.lmax && Number(plotted.depthKm) === asked.depthKm,
      `the plot (${JSON.stringify(plotted)}) is not the server's spectrum of the state (lmax ${asked.lmax}, ${asked.depthKm} km)`);
    const most = Math.max(...asked.power.slice(1));
    check(plotted.circles === asked.power.slice(1).filter((p) => p > 0 && p >= most * 1e-6).length && /4π-normalised/.test(plotted.note),
      `the plot shows ${plotted.circles} degrees, the server gives ${asked.power.length - 1} (note '${plotted.note}')`);
    // A picture's pixels: grey levels on a 48 x 24 grid, and the grey (r = g = b) and coloured
    // pixels of the upper and lower halves (the background, black, counts as neither).
    const look = (id) => page.evaluate((id) => {
      const img = document.getElementById(id);
      const c = document.createElement('canvas');
      c.width = img.naturalWidth;
      c.height = img.naturalHeight;
      const g = c.getContext('2d');
      g.drawImage(img, 0, 0);
      const d = g.getImageData(0, 0, c.width, c.height).data;
      const grid = [], halves = [{ grey: 0, colour: 0 }, { grey: 0, colour: 0 }];
      for (let y = 0; y < c.height; y++)
        for (let x = 0; x < c.width; x++) {
          const i = 4 * (y * c.width + x), [r, gg, b] = [d[i], d[i + 1], d[i + 2]];
          if (Math.max(r, gg, b) < 30) continue;
          halves[y < c.height / 2 ? 0 : 1][r === gg && gg === b ? 'grey' : 'colour']++;
        }
      for (let j = 0; j < 24; j++)
        for (let k = 0; k < 48; k++) {
          const i = 4 * (Math.floor((j + 0.5) * c.height / 24) * c.width + Math.floor((k + 0.5) * c.width / 48));
          grid.push((d[i] + d[i + 1] + d[i + 2]) / 3);
        }
      const box = img.parentElement.getBoundingClientRect();
      return { width: c.width, height: c.height, paneWidth: box.width * devicePixelRatio, grid, halves };
    }, id);
    const map0 = await look('mapImage');
    check(Math.abs(map0.width - map0.paneWidth) <= 2, `the map is ${map0.width} px wide for a pane of ${map0.paneWidth} device pixels`);
    const header = await page.evaluate(() => window.__raypc.slices.map.header);
    check(header.width === map0.width && header.projection === 'mollweide', `the map's header: ${JSON.stringify(header)}`);

    // The slider: another depth, another map.
    const before = (await shown()).map;
    await page.fill('#mapDepthValue', '2000');
    await page.press('#mapDepthValue', 'Enter');
    await nextPicture('map', before);
    check((await rState(page)).map.depthKm === 2000, `map.depthKm after typing 2000: ${(await rState(page)).map.depthKm}`);
    const map1 = await look('mapImage');
    if (process.env.RAYPC_TEST_DEBUG) await page.screenshot({ path: join(process.env.RAYPC_TEST_DEBUG, 'slices.png') });
    const changed = map0.grid.filter((v, i) => Math.abs(v - map1.grid[i]) > 8).length;
    console.log(`  map at 660 vs 2000 km: ${changed} of ${map0.grid.length} grid points differ`);
    check(changed > 15, `the map at 2000 km looks like the one at 660 km (${changed} grid points differ)`);

    // The brushes: the northern hemisphere selected, the southern half of the map grey.
    const b2 = (await shown()).map;
    await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, brushes: [{ name: 'lat', min: 0, max: 90 }] }); });
    await nextPicture('map', b2);
    const grey = await look('mapImage');
    console.log(`  brushed lat 0..90: upper half ${JSON.stringify(grey.halves[0])}, lower half ${JSON.stringify(grey.halves[1])}; unbrushed ${JSON.stringify(map1.halves)}`);
    // (White, the blue-white-red map's zero, counts as grey too: the halves are compared with themselves.)
    check(grey.halves[1].colour < 0.2 * map1.halves[1].colour && grey.halves[0].colour > 0.6 * map1.halves[0].colour,
      `brushing the north: the lower half ${JSON.stringify(grey.halves[1])}, the upper ${JSON.stringify(grey.halves[0])}; unbrushed ${JSON.stringify(map1.halves)}`);

    // The pointer: the map's centre is the equator on the central meridian; the readout gives the
    // probe's value there.
    const img = await page.locator('#mapImage').boundingBox();
    const dpr = await page.evaluate(() => devicePixelRatio);
    const centre = [img.x + header.centre[0] / dpr, img.y + header.centre[1] / dpr];
    await page.mouse.move(centre[0], centre[1]);
    await page.waitForFunction(() => /°N|°S/.test(document.getElementById('mapReadout').textContent), null, { timeout: 10000 })
      .catch(async () => { throw new TestFailure(`no readout at the map's centre: '${await page.textContent('#mapReadout')}'`); });
    const readout = await page.textContent('#mapReadout');
    const m = readout.match(/^([0-9.]+)°([NS]) ([0-9.]+)°([EW]), 2000 km deep: .* (-?[0-9.]+(?:e[-+]?[0-9]+)?) [^ ]*$/);
    check(m, `the readout at the map's centre: '${readout}'`);
    const lat = Number(m[1]) * (m[2] === 'S' ? -1 : 1), lon = Number(m[3]) * (m[4] === 'W' ? -1 : 1);
    const probe = await (await fetch(`${url}api/probe?step=${(await rState(page)).step}&lat=${lat}&lon=${lon}&depthKm=2000&var=${encodeURIComponent((await rState(page)).color.variable)}`)).json();
    const value = Object.values(probe.values)[0].value;
    console.log(`  readout at the centre: '${readout}'; probe there: ${value}`);
    check(Math.abs(lat) < 1.5 && Math.abs(lon) < 1.5, `the map's centre reads ${lat}, ${lon}, not the equator on the central meridian`);
    check(Math.abs(Number(m[5]) - value) <= 0.02 * Math.abs(value) + 0.5, `the readout '${readout}' is not the probe's ${value} there`);

    // Two clicks: the section's start and end; a new section picture.
    const s0 = (await shown()).section;
    await page.mouse.click(centre[0], centre[1]);
    await page.mouse.click(centre[0] + 0.25 * header.scale / dpr * 2, centre[1] - 0.2 * header.scale / dpr * 2);
    await nextPicture('section', s0);
    const sec = (await rState(page)).section;
    console.log(`  section after two clicks: ${JSON.stringify(sec)}`);
    check(Math.abs(sec.from.latDeg) < 1 && Math.abs(sec.from.lonDeg) < 1, `the first click set the start to ${JSON.stringify(sec.from)}`);
    check(sec.to.latDeg > 5 && sec.to.lonDeg > 5, `the second click set the end to ${JSON.stringify(sec.to)} (north-east of the centre)`);

    // The state holds the map: a reload of the page's URL brings it back.
    await page.waitForFunction(() => location.hash.includes('state='), null, { timeout: 5000 });
    const hashUrl = await page.evaluate(() => location.href);
    const again = await openUi(context, hashUrl);
    await waitConverged(again);
    const reloaded = await again.evaluate(() => window.__raypc.state());
    check(reloaded.map.depthKm === 2000 && JSON.stringify(reloaded.section) === JSON.stringify(sec),
      `after a reload: map ${JSON.stringify(reloaded.map)}, section ${JSON.stringify(reloaded.section)}`);
    check(await again.inputValue('#mapDepthValue') === '2000', `the depth field after a reload: ${await again.inputValue('#mapDepthValue')}`);
    // The section by azimuth and length: the end the UI sets is where the server measures that
    // azimuth and length (the section picture's header), and the fields show them.
    const s1 = (await shown()).section;
    await page.fill('#sectionFrom', '-20, 40');
    await page.press('#sectionFrom', 'Enter');
    await nextPicture('section', s1);
    const s2 = (await shown()).section;
    await page.fill('#sectionAzimuth', '30');
    await page.fill('#sectionLength', '50');
    await page.press('#sectionLength', 'Enter');
    // Leaving the azimuth field commits it with the length shown then (a picture of its own): wait
    // for the picture of the end the Enter set (the state's end, which the server holds as float32).
    await nextPicture('section', s2);
    await page.waitForFunction(() => {
      const h = window.__raypc.slices.section.header, to = window.__raypc.state().section.to;
      return h && Math.abs(h.to[0] - to.latDeg) < 1e-4 && Math.abs(h.to[1] - to.lonDeg) < 1e-4 && document.getElementById('sectionImage').complete;
    }, null, { timeout: 20000 }).catch(async () => {
      throw new TestFailure(`no section picture of the end set by azimuth and length: ${JSON.stringify(await page.evaluate(() => [window.__raypc.slices.section.header, window.__raypc.state().section]))}`);
    });
    const arc = await page.evaluate(() => window.__raypc.slices.section.header);
    const fields = [await page.inputValue('#sectionAzimuth'), await page.inputValue('#sectionLength'), await page.textContent('#sectionLengthKm')];
    console.log(`  azimuth 30, length 50 from 20S 40E: to ${JSON.stringify((await rState(page)).section.to)}; the server measures azimuth ${arc.azimuthDeg}, length ${arc.lengthDeg} deg, ${arc.lengthKm} km; fields ${JSON.stringify(fields)}`);
    check(Math.abs(arc.azimuthDeg - 30) < 0.05 && Math.abs(arc.lengthDeg - 50) < 0.02,
      `the section set by azimuth 30 and length 50 has azimuth ${arc.azimuthDeg} and length ${arc.lengthDeg} (the server's)`);
    check(Math.abs(Number(fields[1]) - 50) <= 0.1 && /^5\d\d\d km$/.test(fields[2]), `the fields show ${JSON.stringify(fields)}`);

    // Back to the volume's plot: the marks go.
    await page.click('#pcTabVolume');
    await page.waitForFunction(() => window.__raypc.state().map.showInView === false, null, { timeout: 5000 })
      .catch(() => { throw new TestFailure('leaving the tab left map.showInView on'); });
  },

  // "?" shows the mouse and keyboard help; Escape closes it.
  // The Features panel: two polar caps of the contest-layout fixture are two tracks over
  // the three steps with no events, as `raypc features --tracks` finds them; the table, a track's
  // timeline, the flux plot, the time–depth picture and the tracks' CSV.
  async features({ context, url, tmp, raypc, dataset }) {
    const page = await openUi(context, url);
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(e.message));
    await waitConverged(page);
    const brushes = [{ name: 'depth', min: 0, max: 660 }, { name: 'lat', min: -90, max: -60 }, { name: 'lat', min: 60, max: 90 }];
    await page.evaluate((b) => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, step: 2, brushes: b }); }, brushes);
    await waitConverged(page);
    check(await page.evaluate(() => window.__raypc.featureAnswers.length === 0), 'the closed panel asked for features');
    await page.click('#featuresDetails summary');
    await page.waitForFunction(() => window.__raypc.featureAnswers.some((f) => f) && window.__raypc.timeDepthPictures.length > 0, null, { timeout: 30000 })
      .catch(async () => { throw new TestFailure(`no features after opening the panel; note: ${await page.textContent('#featuresNote')}; errors: ${await page.evaluate(() => window.__raypc.errors.join('; '))}`); });
    const f = await page.evaluate(() => window.__raypc.featureAnswers.filter((x) => x).at(-1));
    console.log(`  ${f.tracks.length} tracks, ${f.events.length} events; note: ${await page.textContent('#featuresNote')}`);
    check(f.level === 0 && f.steps.length === 3, `level ${f.level}, ${f.steps.length} steps`);
    check(f.tracks.length === 2 && f.tracks.every((t) => t.firstStep === 0 && t.lastStep === 2) && f.events.length === 0,
      `two caps should be two tracks over steps 0–2 without events: ${JSON.stringify(f.tracks.map((t) => [t.track, t.firstStep, t.lastStep]))}, events ${JSON.stringify(f.events)}`);
    const north = f.tracks.map((t) => t.points[0].centroidLatDeg).sort((a, b) => a - b);
    check(north[0] < -60 && north[1] > 60, `the tracks' centroids are not one per cap: ${north}`);
    check(await page.evaluate(() => document.getElementById('featuresNote').textContent.startsWith('exact')), 'the figures are not labelled exact');

    // The same tracks as the command line's, volume for volume.
    const cli = spawnSync(raypc, ['features', dataset, '--range', 'depth=0:660', '--range', 'lat=-90:-60', '--range', 'lat=60:90',
      '-o', join(tmp, 'f.csv'), '--tracks', join(tmp, 'tracks.csv'), '--quiet'], { encoding: 'utf8', timeout: 60000 });
    check(cli.status === 0, `raypc features: ${cli.stderr}`);
    const cliRows = readFileSync(join(tmp, 'tracks.csv'), 'utf8').trim().split('\n').slice(1).map((l) => l.split(','));
    const uiRows = f.tracks.flatMap((t) => t.points.map((p) => [t.track, p.step, p.feature, p.volumeKm3]));
    check(cliRows.length === uiRows.length && cliRows.every((r) => uiRows.some((u) => u[0] === +r[0] && u[1] === +r[1] && u[2] === +r[3]
      && Math.abs(u[3] - +r[4]) <= 1e-5 * u[3])), `the UI's tracks differ from raypc features --tracks: ${JSON.stringify(uiRows)} vs ${JSON.stringify(cliRows)}`);

    // The table: a row per track; a click chooses the track, draws its timeline and goes to its first step.
    const rows = await page.$$eval('#featuresTable tr[data-track]', (r) => r.length);
    check(rows === 2, `${rows} rows in the tracks' table`);
    await page.click('#featuresTable tr[data-track]');
    await page.waitForFunction(() => window.__raypc.state().step === 0, null, { timeout: 5000 })
      .catch(() => { throw new TestFailure('choosing a track did not move the time slider to its first step'); });
    const timeline = await page.$$eval('#featuresTimeline path.trackDepth, #featuresTimeline circle.point', (e) => e.length);
    check(timeline === 4, `the track's timeline has ${timeline} of its line and three points`);
    // The chosen track's feature is highlighted in the 3D view (amber), and follows it to step 2.
    const amber = () => page.evaluate(() => {
      const { data: d } = window.__viewImageData();
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i] > 150 && d[i + 1] > 0.55 * d[i] && d[i + 1] < 0.9 * d[i] && d[i + 2] < 0.35 * d[i]) n++;
      return n;
    });
    const chosen = await page.evaluate(() => window.__raypc.features.selectedTrack);
    const track = f.tracks.find((t) => t.track === chosen);
    const st0 = await rState(page);
    check(JSON.stringify(st0.features.highlight) === JSON.stringify([track.points[0].feature]),
      `highlight ${JSON.stringify(st0.features.highlight)} for track ${chosen}'s feature ${track.points[0].feature} of step 0`);
    await waitConverged(page);
    const amberShown = await amber();
    await page.click('#featuresClearHighlight');
    await page.waitForFunction(() => window.__raypc.state().features.highlight.length === 0, null, { timeout: 5000 });
    await waitConverged(page);
    const amberCleared = await amber();
    console.log(`  amber pixels: ${amberShown} with track ${chosen} highlighted, ${amberCleared} after Clear highlight`);
    check(amberShown > 300 && amberCleared < amberShown / 10, `the highlighted feature is not seen in amber: ${amberShown} then ${amberCleared} pixels`);
    // Hovering a row highlights its track's feature of the step without choosing the track; leaving the table ends it.
    await page.hover(`#featuresTable tr[data-track="${chosen}"]`);
    await page.waitForFunction((id) => JSON.stringify(window.__raypc.state().features.highlight) === JSON.stringify([id]), track.points[0].feature, { timeout: 5000 })
      .catch(async () => { throw new TestFailure(`hovering track ${chosen}'s row gave the highlight ${JSON.stringify((await rState(page)).features.highlight)}`); });
    await waitConverged(page);
    const amberHovered = await amber();
    const chosenWhileHovering = await page.evaluate(() => window.__raypc.features.selectedTrack);
    await page.mouse.move(1, 1);
    await page.waitForFunction(() => window.__raypc.state().features.highlight.length === 0, null, { timeout: 5000 })
      .catch(() => { throw new TestFailure('leaving the table kept the hovered track highlighted'); });
    await waitConverged(page);
    const amberLeft = await amber();
    console.log(`  amber pixels: ${amberHovered} while hovering track ${chosen}'s row, ${amberLeft} after leaving the table`);
    check(amberHovered > 300 && amberLeft < amberHovered / 10, `hovering a row: ${amberHovered} then ${amberLeft} amber pixels`);
    check(chosenWhileHovering === null, `hovering chose track ${chosenWhileHovering}`);
    await page.click(`#featuresTable tr[data-track="${chosen}"]`);
    await page.evaluate(() => { document.getElementById('step').value = '2'; document.getElementById('step').dispatchEvent(new Event('change')); });
    await page.waitForFunction(() => window.__raypc.state().step === 2, null, { timeout: 5000 });
    const st2 = await rState(page);
    check(JSON.stringify(st2.features.highlight) === JSON.stringify([track.points[2].feature]),
      `at step 2 the highlight is ${JSON.stringify(st2.features.highlight)}, the track's feature there is ${track.points[2].feature}`);
    await page.click('#featuresColorById');
    check((await rState(page)).features.colorById === true, 'the checkbox did not set features.colorById');
    await page.click('#featuresClearHighlight');
    await page.click('#featuresColorById');
    // Sorting by a column reorders the rows.
    const order = () => page.$$eval('#featuresTable tr[data-track]', (r) => r.map((x) => x.dataset.track).join());
    const o1 = await order();
    await page.click('#featuresTable th[data-sort="track"]');
    const o2 = await order();
    await page.click('#featuresTable th[data-sort="track"]');
    const o3 = await order();
    check(o2 !== o3, `sorting by track twice gives ${o2} and ${o3}`);
    console.log(`  table order by volume ${o1}, by track ${o2} then ${o3}`);
    // Flux: the fixture's uniform rising flow: nothing down, no avalanche; the plot drawn.
    check(f.flux && f.flux.depthsKm.length === 4 && f.flux.avalanches.length === 0 && f.flux.steps.every((s) => s.downKm3PerYr.every((v) => v === 0) && s.upKm3PerYr.every((v) => v > 0)),
      `flux of a uniform rising flow: ${JSON.stringify(f.flux?.steps[0])}`);
    check(await page.$$eval('#featuresFlux path', (p) => p.length) >= 8, 'the flux plot has no lines');
    // The time–depth picture: drawn at the panel's width, coloured where the caps are.
    const pic = await page.evaluate(() => {
      const img = document.getElementById('featuresTimeDepth');
      const c = document.createElement('canvas');
      c.width = img.naturalWidth; c.height = img.naturalHeight;
      const g = c.getContext('2d');
      g.drawImage(img, 0, 0);
      const d = g.getImageData(0, 0, c.width, c.height).data;
      // Viridis' top (the selected shells' share) is yellow: the upper 660 km of every step's column.
      let yellow = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i] > 200 && d[i + 1] > 180 && d[i + 2] < 100) yellow++;
      return { w: c.width, h: c.height, yellow };
    });
    console.log(`  time-depth picture ${pic.w}x${pic.h}, ${pic.yellow} yellow pixels`);
    check(pic.w >= 320 && pic.yellow > 0.05 * pic.w * pic.h, `time-depth picture ${JSON.stringify(pic)}`);
    // The tracks' CSV: the command line's columns and rows.
    const [csv] = await Promise.all([page.waitForEvent('download', { timeout: 10000 }), page.click('#featuresTracksCsv')])
      .catch(async (e) => { throw new TestFailure(`no download of the tracks' CSV: ${e.message.split('\n')[0]}; errors: ${await page.evaluate(() => window.__raypc.errors.join('; '))} ${pageErrors.join('; ')}`); });
    await csv.saveAs(join(tmp, 'ui-tracks.csv'));
    const uiCsv = readFileSync(join(tmp, 'ui-tracks.csv'), 'utf8').trim().split('\n');
    const cliCsv = readFileSync(join(tmp, 'tracks.csv'), 'utf8').trim().split('\n');
    check(uiCsv.join('\n') === cliCsv.join('\n'), `the tracks' CSV differs from raypc features --tracks: ${uiCsv[0]} (${uiCsv.length} lines) vs ${cliCsv[0]} (${cliCsv.length})`);
    // The time–depth picture's values: the table of raypc stats --profile, byte for byte.
    const [tdCsv] = await Promise.all([page.waitForEvent('download', { timeout: 10000 }), page.click('#featuresTimeDepthCsv')])
      .catch(async (e) => { throw new TestFailure(`no download of the time-depth CSV: ${e.message.split('\n')[0]}; errors: ${await page.evaluate(() => window.__raypc.errors.join('; '))}`); });
    await tdCsv.saveAs(join(tmp, 'ui-time-depth.csv'));
    const cliProfile = spawnSync(raypc, ['stats', dataset, '--range', 'depth=0:660', '--range', 'lat=-90:-60', '--range', 'lat=60:90',
      '-o', join(tmp, 's.csv'), '--profile', join(tmp, 'profile.csv'), '--quiet'], { encoding: 'utf8', timeout: 60000 });
    check(cliProfile.status === 0, `raypc stats --profile: ${cliProfile.stderr}`);
    const uiProfile = readFileSync(join(tmp, 'ui-time-depth.csv'), 'utf8'), cliProfileText = readFileSync(join(tmp, 'profile.csv'), 'utf8');
    check(uiProfile === cliProfileText && uiProfile.split('\n').length > 10,
      `the time-depth CSV differs from raypc stats --profile: ${uiProfile.split('\n')[0]} (${uiProfile.length} bytes) vs ${cliProfileText.split('\n')[0]} (${cliProfileText.length})`);

    // Stalls timed by the deepest point: the caps reach down to 660 km, so both stall there in every
    // step (by the mean depth they do not), as `raypc features --stall-by deepest` finds.
    const stallsAt = (x, depth) => x.tracks.map((t) => t.stalls.filter((st) => st.depthKm === depth).map((st) => `${st.firstStep}-${st.lastStep}${st.left}`).join()).join(';');
    await page.selectOption('#featuresStallBy', 'deepest');
    await page.waitForFunction(() => window.__raypc.featureAnswers.at(-1)?.stallBy === 'deepest', null, { timeout: 30000 })
      .catch(async () => { throw new TestFailure(`choosing stall by deepest asked nothing: state ${JSON.stringify((await rState(page)).features)}`); });
    const deep = await page.evaluate(() => window.__raypc.featureAnswers.at(-1));
    console.log(`  stalls at 660 km by mean depth '${stallsAt(f, 660)}', by the deepest point '${stallsAt(deep, 660)}'`);
    check(stallsAt(deep, 660) === '0-2;0-2' && stallsAt(f, 660) === ';', `stalls at 660 km: by mean depth '${stallsAt(f, 660)}', by the deepest point '${stallsAt(deep, 660)}'`);
    const cliDeep = spawnSync(raypc, ['features', dataset, '--range', 'depth=0:660', '--range', 'lat=-90:-60', '--range', 'lat=60:90',
      '-o', join(tmp, 'f.csv'), '--stalls', join(tmp, 'stalls.csv'), '--stall-by', 'deepest', '--quiet'], { encoding: 'utf8', timeout: 60000 });
    check(cliDeep.status === 0, `raypc features --stall-by deepest: ${cliDeep.stderr}`);
    const cliStalls = readFileSync(join(tmp, 'stalls.csv'), 'utf8').trim().split('\n').slice(1).filter((l) => l.split(',')[1] === '660').length;
    check(cliStalls === 2, `raypc features --stall-by deepest finds ${cliStalls} stalls at 660 km`);

    // While it waits the note says how many steps the server has done (GET /api/job-progress of the
    // request's job): the answer held back 1.5 s, the note reads "step 3 of 3 done".
    const asked = [];
    page.on('request', (r) => { if (/api\/(features|job-progress)/.test(r.url())) asked.push(r.url()); });
    await page.route('**/api/features?*', async (route) => {
      const answer = await route.fetch();
      await new Promise((r) => setTimeout(r, 1500));
      await route.fulfill({ response: answer });
    });
    await page.click('#featuresFind');
    await page.waitForFunction(() => /step 3 of 3 done/.test(document.getElementById('featuresNote').textContent), null, { timeout: 10000 })
      .catch(async () => { throw new TestFailure(`the note never said the steps done: '${await page.textContent('#featuresNote')}'; asked ${asked.join(' ')}`); });
    await page.unroute('**/api/features?*');
    const jobOf = (u) => new URL(u).searchParams.get('job');
    const featureJob = jobOf(asked.find((u) => u.includes('api/features')));
    check(featureJob && asked.some((u) => u.includes('job-progress') && jobOf(u) === featureJob),
      `the panel asked the progress of another job: ${asked.join(' ')}`);
    console.log(`  while waiting: '${await page.textContent('#featuresNote')}'`);

    // A new selection cancels nothing visible and asks again; no brushes: an empty panel, no error.
    const answers = await page.evaluate(() => window.__raypc.featureAnswers.length);
    await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, brushes: [] }); });
    await page.waitForFunction((n) => window.__raypc.featureAnswers.length > n && window.__raypc.featureAnswers.at(-1) === null, answers, { timeout: 10000 })
      .catch(() => { throw new TestFailure('clearing the brushes did not empty the panel'); });
    check(await page.$$eval('#featuresTable tr', (r) => r.length) === 0, 'rows left in the table without brushes');
    const errors = await page.evaluate(() => window.__raypc.errors);
    check(errors.length === 0, `errors: ${errors.join('; ')}`);
  },

  async help({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    check(!(await page.isVisible('#helpDialog')), 'the help is open before asked for');
    await page.locator('body').press('?');
    await page.waitForSelector('#helpDialog[open]', { timeout: 3000 })
      .catch(() => { throw new TestFailure('"?" did not open the help'); });
    const text = await page.textContent('#helpDialog');
    for (const words of ['orbit', 'pan', 'zoom', 'Escape', 'Space', 'brush'])
      check(text.includes(words), `the help does not mention ${words}: '${text.slice(0, 200)}…'`);
    await page.keyboard.press('Escape');
    await page.waitForFunction(() => !document.getElementById('helpDialog').open, null, { timeout: 3000 })
      .catch(() => { throw new TestFailure('Escape did not close the help'); });
    await page.click('#help');
    await page.waitForSelector('#helpDialog[open]', { timeout: 3000 })
      .catch(() => { throw new TestFailure('the ? button did not open the help'); });
    await page.click('#helpClose');
  },

  // A state saved on a longer series (step 99 on this one) is clamped to
  // the last step with a note and asks for no sample in a loop; a state the server refuses (an
  // unknown brush variable, min > max) changes nothing, sends nothing and shows no figure of its own.
  async load_checks({ context, url, tmp }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const last = (await info(url)).steps.length - 1;
    const start = await rState(page);
    let samples = 0;
    page.on('request', (r) => { if (r.url().includes('api/sample')) samples++; });
    const far = join(tmp, 'far.json');
    writeFileSync(far, JSON.stringify({ ...start, step: 99 }));
    await page.setInputFiles('#load', far);
    await page.waitForFunction(() => /written for step 99/.test(document.getElementById('status').textContent), null, { timeout: 10000 })
      .catch(async () => { throw new TestFailure(`no note of the clamped step; status '${await page.textContent('#status')}'`); });
    await waitConverged(page);
    const clamped = await rState(page);
    check(clamped.step === last, `a state of step 99 shows step ${clamped.step}, expected the last, ${last}`);
    const label = await page.textContent('#stepLabel');
    check(label.startsWith(`step ${last} of`), `the step label after loading step 99: '${label}'`);
    const headerStep = await page.evaluate(() => window.__raypc.headers[window.__raypc.headers.length - 1].step);
    check(headerStep === last, `the picture shows step ${headerStep}, expected ${last}`);
    samples = 0;
    await page.waitForTimeout(2000);
    check(samples <= 1, `${samples} sample requests in the 2 s after loading (a retry loop?)`);

    const before = await rState(page);
    for (const [name, brushes, expect] of [
      ['unknown.json', [{ name: 'pressure', min: 0, max: 1 }], /pressure/],
      ['reversed.json', [{ name: 'depth', min: 700, max: 600 }], /min|max/],
    ]) {
      const file = join(tmp, name);
      writeFileSync(file, JSON.stringify({ ...before, brushes }));
      const sentBefore = await page.evaluate(() => window.__raypc.lastSentId);
      const errorsBefore = await page.evaluate(() => window.__raypc.errors.length);
      await page.setInputFiles('#load', file);
      await page.waitForFunction((n) => window.__raypc.errors.length > n, errorsBefore, { timeout: 10000 })
        .catch(() => { throw new TestFailure(`loading ${name} showed no error`); });
      const msg = await page.evaluate(() => window.__raypc.errors[window.__raypc.errors.length - 1]);
      check(/not applied/.test(msg) && expect.test(msg), `${name}: error '${msg}'`);
      await page.waitForTimeout(300);
      check(JSON.stringify(await rState(page)) === JSON.stringify(before), `${name}: the refused state changed the state in force`);
      check(await page.evaluate(() => window.__raypc.lastSentId) === sentBefore, `${name}: the refused state was sent`);
      const status = await page.textContent('#status');
      check(!/selected/.test(status), `${name}: the status shows a selection: '${status}'`);
    }

    // A state file without an image size (an example state) keeps the view's size,
    // and the picture follows the view when the window is resized.
    const viewImage = (await rState(page)).image;
    const noImage = join(tmp, 'no-image.json');
    const { image: _drop, ...withoutImage } = await rState(page);
    writeFileSync(noImage, JSON.stringify({ ...withoutImage, camera: { ...withoutImage.camera, azimuthDeg: 77 } }));
    const sentNoImage = await page.evaluate(() => window.__raypc.lastSentId);
    await page.setInputFiles('#load', noImage);
    await page.waitForFunction((n) => window.__raypc.lastSentId > n, sentNoImage, { timeout: 10000 })
      .catch(() => { throw new TestFailure('loading a state without an image size sent nothing'); });
    await waitConverged(page);
    const loadedImage = (await rState(page)).image;
    check(loadedImage.width === viewImage.width && loadedImage.height === viewImage.height,
      `a state without an image renders at ${loadedImage.width}x${loadedImage.height}, the view is ${viewImage.width}x${viewImage.height}`);
    await page.setViewportSize({ width: 1100, height: 760 });
    await page.waitForFunction((w) => window.__raypc.state().image.width !== w, loadedImage.width, { timeout: 5000 })
      .catch(() => { throw new TestFailure('after loading a state without an image size, resizing the window did not resize the picture'); });
    await waitConverged(page);

    // The screenshot dialog states the server's limit (GET /api/info) and refuses
    // a size beyond it before sending; a screenshot the server fails is shown as failed.
    const limits = (await info(url)).limits;
    const passes = (await rState(page)).passes;
    const most = Math.min(limits.screenshotPixels, Math.floor(limits.screenshotPixelPasses / passes));
    await page.click('#screenshot');
    const limitText = await page.textContent('#shotLimit');
    check(limitText.includes(most.toLocaleString('en')), `the dialog's limit '${limitText}', the server's ${most} pixels at ${passes} passes`);
    await page.check('input[name="shotSize"][value="custom"]');
    await page.fill('#shotWidth', '8000');
    await page.fill('#shotHeight', '4000');
    let errorsBefore = await page.evaluate(() => window.__raypc.errors.length);
    await page.click('#shotRender');
    await page.waitForFunction((n) => window.__raypc.errors.length > n, errorsBefore, { timeout: 5000 })
      .catch(() => { throw new TestFailure('an 8000 x 4000 screenshot was not refused'); });
    const tooLarge = await page.evaluate(() => window.__raypc.errors[window.__raypc.errors.length - 1]);
    check(/more than the/.test(tooLarge), `8000 x 4000: '${tooLarge}'`);
    check(!/rendering a/.test(await page.textContent('#status')), 'the status says a refused screenshot is rendering');
    await page.click('#shotCancel');
    await page.route('**/api/screenshot', (r) => r.fulfill({ status: 503, contentType: 'text/plain', body: 'screenshot: the server is busy' }));
    errorsBefore = await page.evaluate(() => window.__raypc.errors.length);
    await page.click('#screenshot');
    await page.check('input[name="shotSize"][value="view"]');
    await page.click('#shotRender');
    await page.waitForFunction((n) => window.__raypc.errors.length > n, errorsBefore, { timeout: 5000 })
      .catch(() => { throw new TestFailure('a failed screenshot showed no error'); });
    const failedStatus = await page.textContent('#status');
    check(/screenshot .* failed/.test(failedStatus) && !/rendering a/.test(failedStatus), `the status after a failed screenshot: '${failedStatus}'`);
    await page.unroute('**/api/screenshot');
  },

  // Two tabs hold different states and render independently: each tab's frames carry its own
  // camera, and work in one tab sends no frames to the other.
  async two_tabs({ context, url }) {
    const ds = await info(url);
    const other = { ...ds.defaultState, camera: { ...ds.defaultState.camera, azimuthDeg: 200, elevationDeg: -30 },
      color: { ...ds.defaultState.color, variable: ds.variables[1].name, colorMap: 'cool-to-warm' } };
    const hash = '#state=' + Buffer.from(JSON.stringify(other)).toString('base64url');
    const a = await openUi(context, url);
    const b = await openUi(context, url, { hash });
    const [sa, sb] = [await rState(a), await rState(b)];
    check(sb.camera.azimuthDeg === 200 && sb.color.variable === ds.variables[1].name, `tab 2 state ${JSON.stringify(sb.camera)}`);
    const ha = await a.evaluate(() => window.__raypc.headers.at(-1));
    const hb = await b.evaluate(() => window.__raypc.headers.at(-1));
    check(ha.camera.azimuthDeg === sa.camera.azimuthDeg && hb.camera.azimuthDeg === 200, `frames carry cameras ${ha.camera.azimuthDeg} and ${hb.camera.azimuthDeg}`);
    const pa = await viewPixels(a), pb = await viewPixels(b);
    check(meanAbsDiff(pa, pb) > 2, 'the two tabs show the same image');
    const framesB = await b.evaluate(() => window.__raypc.framesReceived);
    await a.bringToFront();
    await drag(a, 50, 0);
    await waitConverged(a);
    check((await a.evaluate(() => window.__raypc.headers.at(-1).camera.azimuthDeg)) !== sa.camera.azimuthDeg, 'tab 1 did not rotate');
    await b.waitForTimeout(300);
    const framesB2 = await b.evaluate(() => window.__raypc.framesReceived);
    check(framesB2 === framesB, `tab 2 received ${framesB2 - framesB} frames while only tab 1 changed`);
    check(meanAbsDiff(pb, await viewPixels(b)) < 0.5, 'tab 2 image changed while only tab 1 changed');
  },

  // Every example state is a preset button; one click applies it: the state sent carries the
  // preset's brushes, colours and camera (with the current step and image size), the parallel
  // coordinates show its brushes, and the image changes. The selection-over-time plot then holds
  // every step with the current one marked, and with "exact" its value at the current step equals
  // POST /api/selection.
  async presets({ context, url, tmp }) {
    const page = await openUi(context, url);
    await standardView(page);
    const presets = await (await fetch(url + 'api/presets')).json();
    check(presets.length >= 9, `GET /api/presets has ${presets.length} presets, expected the 9 example states`);
    const buttons = await page.evaluate(() => [...document.querySelectorAll('#presets button')].map((b) => ({ name: b.dataset.preset, text: b.textContent })));
    check(JSON.stringify(buttons.map((b) => b.name)) === JSON.stringify(presets.map((p) => p.name)),
      `preset buttons ${JSON.stringify(buttons)} do not match /api/presets`);
    const image = (await rState(page)).image;
    const nSteps = (await info(url)).steps.length;
    let before = await viewPixels(page);
    let step = 0;
    let pathlinesSeen = false;
    const diffs = [];
    for (const p of presets) {
      const sentBefore = await page.evaluate(() => window.__raypc.lastSentId);
      await page.click(`#presets button[data-preset="${p.name}"]`);
      await page.waitForFunction((n) => window.__raypc.lastSentId > n, sentBefore, { timeout: 5000 })
        .catch(() => { throw new TestFailure(`clicking preset ${p.name} sent no state`); });
      await waitConverged(page);
      const shown = await page.evaluate(() => {
        const r = window.__raypc, h = r.headers[r.headers.length - 1];
        return { sent: r.sentLog.find((e) => e.id === h.id), state: r.state(), pc: r.parcoords.brushes(), errors: r.errors };
      });
      // Presets older than state version 7 name no camera.views: the state then has the default, [].
      check(JSON.stringify(shown.sent.brushes) === JSON.stringify(p.state.brushes),
        `${p.name}: the frame shown was rendered with brushes ${JSON.stringify(shown.sent.brushes)}, the preset has ${JSON.stringify(p.state.brushes)}`);
      check(JSON.stringify(shown.state.camera) === JSON.stringify({ ...p.state.camera, views: p.state.camera.views ?? [] }) && shown.state.color.variable === p.state.color.variable &&
        JSON.stringify(shown.state.color.opacity) === JSON.stringify(p.state.color.opacity),
        `${p.name}: camera or colours not applied: ${JSON.stringify(shown.state.camera)} ${JSON.stringify(shown.state.color)}`);
      // The preset's step (the last one when the dataset has fewer), its pathlines or none, the image
      // size of the view; and a one-line description naming its brushes.
      step = Math.min(p.state.step ?? 0, nSteps - 1);
      check(shown.state.step === step && JSON.stringify(shown.state.image) === JSON.stringify(image),
        `${p.name}: step ${shown.state.step} and image ${JSON.stringify(shown.state.image)}, expected step ${step} and ${JSON.stringify(image)}`);
      const namesPathlines = Boolean(p.state.pathlines?.visible);
      check(shown.state.pathlines.visible === namesPathlines,
        `${p.name}: pathlines ${shown.state.pathlines.visible ? 'on' : 'off'}${pathlinesSeen ? ' after a preset that showed them' : ''}, the preset ${namesPathlines ? 'shows' : 'does not show'} them`);
      pathlinesSeen ||= namesPathlines;
      const note = await page.textContent('#presetNote');
      check(p.state.brushes.every((b) => note.includes(b.name)) && note.includes(`step ${step}`), `${p.name}: preset description '${note}'`);
      const pcNames = shown.pc.map((b) => b.name).sort().join(',');
      check(pcNames === p.state.brushes.map((b) => b.name).sort().join(','), `${p.name}: parallel coordinates show brushes on ${pcNames}`);
      const after = await viewPixels(page);
      const d = meanAbsDiff(before, after);
      diffs.push(`${p.name} ${d.toFixed(2)}`);
      check(d > 0.3, `${p.name}: the image hardly changed (mean difference ${d.toFixed(2)} grey levels)`);
      before = after;
    }
    console.log(`  image change per preset: ${diffs.join(', ')}`);
    check(pathlinesSeen, 'no preset showed pathlines, so resetting them was not tested');

    // A preset's open ends read as such (task 1's T anomaly -1e4 … -25 K is "≤ -25");
    // once its brushes are cleared (Escape) it is no longer highlighted and its note says so.
    await page.click('#presets button[data-preset="task1-slabs-660km"]');
    await waitConverged(page);
    const task1Note = await page.textContent('#presetNote');
    check(/temperature anomaly ≤ -25 K/.test(task1Note) && !/e\+4|10000/.test(task1Note), `task 1's note: '${task1Note}'`);
    check(await page.evaluate(() => document.querySelector('#presets button.active')?.dataset.preset) === 'task1-slabs-660km',
      'task 1 is not highlighted after its click');
    await page.locator('#view3d').click({ position: { x: 5, y: 5 } }).catch(() => {});
    await page.keyboard.press('Escape');
    await waitConverged(page);
    check((await rState(page)).brushes.length === 0, 'Escape left brushes');
    check(await page.evaluate(() => document.querySelector('#presets button.active') === null), 'a preset stays highlighted after its brushes were cleared');
    const clearedNote = await page.textContent('#presetNote');
    check(/brushes changed/.test(clearedNote), `the note after clearing the brushes: '${clearedNote}'`);
    await page.click(`#presets button[data-preset="${presets[presets.length - 1].name}"]`);
    await waitConverged(page);

    // Selection over time of the last preset (brushed): exact by default (level 0), then approximate
    // at level 1 and labelled so.
    const last = presets[presets.length - 1];
    check(last.state.brushes.length > 0, `the last preset ${last.name} has no brushes`);
    const waitStats = (level) => page.waitForFunction((lv) => {
      const st = window.__raypc.stats;
      return st && st.level === lv && JSON.stringify(st) !== 'null';
    }, level, { timeout: 30000 }).catch(() => { throw new TestFailure(`no selection statistics at level ${level}`); });
    await waitStats(0);
    const plot = await page.evaluate(() => ({
      stats: window.__raypc.stats,
      dots: document.querySelectorAll('#statsTime circle.step').length,
      marked: document.querySelectorAll('#statsTime line.current').length,
      profile: document.querySelector('#statsProfile path.profile')?.getAttribute('d')?.length ?? 0,
    }));
    check(plot.stats.steps.length === nSteps && plot.dots === nSteps && plot.marked === 1 && plot.profile > 20,
      `selection-over-time plot: ${plot.stats.steps.length} steps, ${plot.dots} dots, ${plot.marked} marks, profile path of ${plot.profile} characters`);
    // The statistics shown may still be the previous preset's for a moment (they are asked for after a
    // pause): wait until the step's figure is the exact selection of this state.
    const sel = await postJson(url + 'api/selection', await rState(page));
    await page.waitForFunction(([st, f]) => {
      const now = window.__raypc.stats?.steps.find((s) => s.step === st);
      return window.__raypc.stats?.level === 0 && now && Math.abs(now.fractionOfMantle - f) < 1e-12 &&
        /^exact: now /.test(document.getElementById('statsNote').textContent);
    }, [step, sel.body.fractionOfMantle], { timeout: 30000 }).catch(() => {});
    const exact = await page.evaluate(() => window.__raypc.stats);
    const exactNote = await page.textContent('#statsNote');
    check(/^exact: now /.test(exactNote), `statistics note '${exactNote}'`);
    const now = exact.steps.find((s) => s.step === step);
    check(sel.status === 200 && Math.abs(now.fractionOfMantle - sel.body.fractionOfMantle) < 1e-12,
      `exact statistics ${now.fractionOfMantle} at step ${step}, POST /api/selection ${JSON.stringify(sel.body)}`);
    const profileSum = exact.profile.volumeKm3.reduce((a, b) => a + b, 0);
    check(Math.abs(profileSum - now.volumeKm3) <= 1e-6 * Math.max(1, now.volumeKm3), `depth profile sums to ${profileSum}, the step's volume is ${now.volumeKm3}`);
    const selectionText = await page.textContent('#selectionValue');
    check(selectionText.includes(`${(now.fractionOfMantle * 100).toFixed(2)} %`) && exactNote.includes(`now ${(now.fractionOfMantle * 100).toFixed(2)} %`),
      `the selection says '${selectionText}', the statistics '${exactNote}'`);
    const [csv] = await Promise.all([page.waitForEvent('download'), page.click('#statsCsv')]);
    const csvFile = join(tmp, 'stats.csv');
    await csv.saveAs(csvFile);
    const rows = readFileSync(csvFile, 'utf8').trim().split('\n');
    check(rows[0] === 'step,time_myr,selected_volume_km3,selected_percent_of_mantle,level' && rows.length === nSteps + 1, `statistics CSV: ${rows.join(' | ')}`);
    // A step change is drawn from the answer the panel has (every step's figures and profiles): no
    // new request, the new step's depth profile and "now" figure.
    const asked = await page.evaluate(() => window.__raypc.statsRequests);
    const other = (step + 1) % nSteps;
    await page.evaluate((st) => window.__raypc.setState({ ...window.__raypc.state(), step: st }), other);
    await page.waitForFunction((st) => window.__raypc.stats?.profile.step === st, other, { timeout: 30000 })
      .catch(() => { throw new TestFailure(`the depth profile did not follow the step to ${other}`); });
    await page.waitForTimeout(600); // past the requests' debounce
    const moved = await page.evaluate(() => ({ stats: window.__raypc.stats, asked: window.__raypc.statsRequests,
      note: document.getElementById('statsNote').textContent }));
    const otherNow = moved.stats.steps.find((s) => s.step === other);
    const otherSum = moved.stats.profile.volumeKm3.reduce((a, b) => a + b, 0);
    check(moved.asked === asked, `a step change asked for the statistics again (${asked} -> ${moved.asked} requests)`);
    check(Math.abs(otherSum - otherNow.volumeKm3) <= 1e-6 * Math.max(1, otherNow.volumeKm3) &&
      moved.note.includes(`now ${(otherNow.fractionOfMantle * 100).toFixed(2)} %`),
      `after the step change to ${other}: profile sums to ${otherSum}, the step's volume is ${otherNow.volumeKm3}; note '${moved.note}'`);
    await page.uncheck('#statsExact');
    await waitStats(1);
    const approx = await page.textContent('#statsNote');
    check(/^approximate \(level 1 grid\)/.test(approx), `level-1 statistics note '${approx}'`);
  },

  // Pictures at the screen's resolution: at devicePixelRatio 2 the still frame has the canvas's
  // size in device pixels (CSS size x 2); the Max size setting caps its longer side keeping the
  // aspect; the screenshot dialog offers the view size and 2x of it and renders a custom size.
  async resolution({ context, url, tmp }) {
    const page = await openUi(context, url);
    const view = () => page.evaluate(() => {
      const c = document.getElementById('view3d'), r = window.__raypc, h = r.headers.at(-1);
      return { dpr: devicePixelRatio, css: [c.clientWidth, c.clientHeight], canvas: [c.width, c.height], frame: [h.width, h.height], image: r.state().image };
    });
    const v = await view();
    check(v.dpr === 2, `devicePixelRatio ${v.dpr}, expected 2`);
    check(v.canvas[0] === Math.round(v.css[0] * 2) && v.canvas[1] === Math.round(v.css[1] * 2), `canvas ${v.canvas} for CSS size ${v.css} at ratio 2`);
    check(v.frame[0] === v.canvas[0] && v.frame[1] === v.canvas[1] && v.image.width === v.canvas[0] && v.image.height === v.canvas[1],
      `the still frame is ${v.frame.join('x')} (state ${v.image.width}x${v.image.height}), the canvas ${v.canvas.join('x')} device pixels`);
    console.log(`  still frame ${v.frame.join('x')} for a ${v.css.join('x')} CSS-pixel view at ratio 2`);

    await page.selectOption('#maxSize', '512');
    await waitConverged(page);
    const c = await view();
    const longer = Math.max(...c.frame), aspect = c.frame[0] / c.frame[1], viewAspect = c.canvas[0] / c.canvas[1];
    check(longer === 512 && Math.abs(aspect - viewAspect) < 0.01, `with Max size 512 the frame is ${c.frame.join('x')} for a view of aspect ${viewAspect.toFixed(3)}`);

    const image = (await rState(page)).image;
    await page.click('#screenshot');
    const labels = await page.evaluate(() => ({ view: document.getElementById('shotViewSize').textContent, x2: document.getElementById('shot2xSize').textContent }));
    check(labels.view === `${image.width} × ${image.height}` && labels.x2 === `${2 * image.width} × ${2 * image.height}`, `screenshot sizes offered: ${JSON.stringify(labels)} for ${JSON.stringify(image)}`);
    await page.click('#shotCancel');
    const size = await screenshot(page, join(tmp, 'custom.png'), 'custom', [300, 180]);
    check(size.width === 300 && size.height === 180, `the custom screenshot is ${size.width}x${size.height}, asked 300x180`);
    const doubled = await screenshot(page, join(tmp, 'double.png'), '2x');
    check(doubled.width === 2 * image.width && doubled.height === 2 * image.height, `the 2x screenshot is ${doubled.width}x${doubled.height} for ${image.width}x${image.height}`);
  },

  // Context: reference shells and coastlines change the picture and are in the state; the shell
  // depths are editable; the legend shows the variable with its units; `raypc render` with the
  // saved state draws them too.
  async context({ context, url, tmp, raypc, dataset }) {
    const page = await openUi(context, url);
    await standardView(page);
    // The first view shows the 410 and 660 km shells and the legend: off for a plain picture.
    const defaultDepths = JSON.stringify((await info(url)).defaultState.reference.shells.depthsKm);
    await page.uncheck('#refShells');
    await page.uncheck('#legend');
    await waitConverged(page);
    const plain = await viewPixels(page);
    await page.check('#refShells');
    await waitConverged(page);
    const s1 = await rState(page);
    check(s1.reference.shells.visible && JSON.stringify(s1.reference.shells.depthsKm) === defaultDepths,
      `state.reference.shells after ticking Shells: ${JSON.stringify(s1.reference.shells)}`);
    const shells = await viewPixels(page);
    const dShells = meanAbsDiff(plain, shells);
    check(dShells > 0.3, `the reference shells hardly changed the image (${dShells.toFixed(2)})`);
    await page.fill('#refDepths', '660');
    await page.dispatchEvent('#refDepths', 'change');
    await waitConverged(page);
    check(JSON.stringify((await rState(page)).reference.shells.depthsKm) === '[660]', `edited depths: ${JSON.stringify((await rState(page)).reference.shells)}`);
    const one = await viewPixels(page);
    check(meanAbsDiff(shells, one) > 0.1, `one shell looks like ${defaultDepths}`);
    await page.uncheck('#refShells');
    await page.check('#refCoastlines');
    await page.check('#refGraticule');
    await waitConverged(page);
    const s2 = await rState(page);
    check(s2.reference.coastlines.visible && s2.reference.graticule.visible && !s2.reference.shells.visible, `state.reference: ${JSON.stringify(s2.reference)}`);
    const coast = await viewPixels(page);
    const dCoast = meanAbsDiff(plain, coast);
    check(dCoast > 0.2, `coastlines and graticule hardly changed the image (${dCoast.toFixed(2)})`);
    await page.check('#legend');
    await waitConverged(page);
    const legend = await page.evaluate(() => [...document.querySelectorAll('#legends .legendTitle')].map((e) => e.textContent));
    const variable = s2.color.variable;
    check(legend.length === 1 && legend[0].startsWith(variable) && /\[.+\]/.test(legend[0]), `legend titles ${JSON.stringify(legend)} for ${variable}`);
    console.log(`  image change: shells ${dShells.toFixed(2)}, coastlines and graticule ${dCoast.toFixed(2)}`);

    // The same state rendered by `raypc render` shows them: with and without coastlines differ.
    const state = await rState(page);
    const withFile = join(tmp, 'with.json'), withoutFile = join(tmp, 'without.json');
    writeFileSync(withFile, JSON.stringify(state));
    writeFileSync(withoutFile, JSON.stringify({ ...state, legend: false, reference: { ...state.reference, coastlines: { ...state.reference.coastlines, visible: false }, graticule: { ...state.reference.graticule, visible: false } } }));
    for (const [f, out] of [[withFile, 'with.png'], [withoutFile, 'without.png']]) {
      const r = spawnSync(raypc, ['render', dataset, '--state', f, '-o', join(tmp, out), '--passes', '1', '--size', '256x256'], { encoding: 'utf8', timeout: 60000 });
      check(r.status === 0, `raypc render --state ${f}: ${r.stderr}`);
    }
    check(!readFileSync(join(tmp, 'with.png')).equals(readFileSync(join(tmp, 'without.png'))), 'raypc render drew no coastlines, graticule or legend');
  },

  // The colour editor: switching the variable picks defaults that suit it (a sequential map over the
  // data range for temperature, a diverging map centred on 0 for the anomaly, a fresh opacity ramp);
  // colour points added on the bar and recoloured change the picture and survive save/load; a
  // reversed map changes it too; ParaView colour-map JSON round-trips through export and import
  // (colour points exactly, at their values).
  async colors({ context, url, tmp }) {
    const page = await openUi(context, url);
    await standardView(page);
    await page.selectOption('#variable', 'temperature');
    await waitConverged(page);
    const t = await rState(page);
    const tMin = Number(await page.inputValue('#rangeMin'));
    check(t.color.colorMap === 'batlow' && t.color.range === null && tMin > 0 && JSON.stringify(t.color.opacity) === '[[0,0],[1,0.5]]',
      `temperature defaults: ${JSON.stringify(t.color)}, range min ${tMin}`);
    await page.selectOption('#variable', 'temperature anomaly');
    await waitConverged(page);
    const a = await rState(page);
    const [aMin, aMax] = [Number(await page.inputValue('#rangeMin')), Number(await page.inputValue('#rangeMax'))];
    check(a.color.colorMap === 'vik' && aMin < 0 && Math.abs(aMin + aMax) < 1e-6 * aMax, `anomaly defaults: ${a.color.colorMap} ${aMin}..${aMax}`);
    const before = await viewPixels(page);

    // A colour point in the middle of the bar, recoloured bright green.
    await page.locator('#tf').scrollIntoViewIfNeeded();
    const bar = await page.evaluate(() => {
      const r = document.getElementById('tf').getBoundingClientRect();
      return { x: r.x + r.width / 2, y: r.y + r.height - 22 - 14 + 4 + 7 };
    });
    await page.mouse.click(bar.x, bar.y);
    await waitConverged(page);
    const p1 = (await rState(page)).color.points;
    check(p1.length === 8, `clicking the colour bar made ${p1.length} colour points, expected the map's 7 and the new one`);
    await page.evaluate(() => {
      const input = document.getElementById('tfPointColor');
      input.value = '#00ff00';
      input.dispatchEvent(new Event('input'));
    });
    await waitConverged(page);
    const edited = await rState(page);
    const green = edited.color.points.find((p) => p[1] === 0 && p[2] === 1 && p[3] === 0);
    check(green && Math.abs(green[0] - 0.5) < 0.03, `the selected point did not turn green: ${JSON.stringify(edited.color.points)}`);
    const recolored = await viewPixels(page);
    const dColor = meanAbsDiff(before, recolored);
    check(dColor > 0.3, `recolouring the middle of the map hardly changed the image (${dColor.toFixed(2)})`);

    // Save/load: the points come back and render the same.
    await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, color: { ...s.color, points: [] } }); });
    await waitConverged(page);
    await page.evaluate((s) => window.__raypc.setState(s), edited);
    await waitConverged(page);
    check(JSON.stringify((await rState(page)).color.points) === JSON.stringify(edited.color.points), 'colour points lost on load');
    check(meanAbsDiff(recolored, await viewPixels(page)) < 1, 'the reloaded colour points render differently');

    // ParaView JSON: export, then import it over the plain map.
    const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#pvExport')]);
    const file = join(tmp, 'pv.json');
    await dl.saveAs(file);
    const pv = JSON.parse(readFileSync(file, 'utf8'));
    check(Array.isArray(pv) && pv[0].RGBPoints.length === edited.color.points.length * 4 && pv[0].Points.length === edited.color.opacity.length * 4,
      `exported ParaView JSON: ${JSON.stringify(pv).slice(0, 200)}`);
    await page.selectOption('#colorMap', 'vik');
    await waitConverged(page);
    check((await rState(page)).color.points.length === 0, 'choosing a map kept the colour points');
    // The file is read asynchronously: wait for the state it makes to be sent before waiting for
    // its frame (else the converged frame of the plain map may pass for it).
    const sentBeforeImport = await page.evaluate(() => window.__raypc.lastSentId);
    await page.setInputFiles('#pvImport', file);
    await page.waitForFunction((n) => window.__raypc.lastSentId > n, sentBeforeImport, { timeout: 5000 })
      .catch(() => { throw new TestFailure('importing the ParaView colour map sent no state'); });
    await waitConverged(page);
    const imported = await rState(page);
    check(imported.color.points.length === edited.color.points.length && Math.abs(imported.color.range[0] - pv[0].RGBPoints[0]) < 1e-3 * aMax,
      `imported ParaView map: ${imported.color.points.length} points, range ${JSON.stringify(imported.color.range)}`);
    const dImport = meanAbsDiff(recolored, await viewPixels(page));
    check(dImport < 0.5, `the imported map renders unlike the exported one (${dImport.toFixed(2)})`);
    const bad = join(tmp, 'bad-pv.json');
    writeFileSync(bad, JSON.stringify([{ Name: 'x', RGBPoints: [0, 0, 0] }]));
    const errorsBefore = await page.evaluate(() => window.__raypc.errors.length);
    await page.setInputFiles('#pvImport', bad);
    await page.waitForFunction((n) => window.__raypc.errors.length > n, errorsBefore, { timeout: 5000 });
    check(/RGBPoints/.test(await page.textContent('#error')), `bad ParaView file: ${await page.textContent('#error')}`);
    // Nested 100 000 deep (such JSON crashed the server's parser; the browser parses
    // colour maps itself): one short error, and the page goes on.
    const deep = join(tmp, 'deep-pv.json');
    writeFileSync(deep, '['.repeat(100000) + ']'.repeat(100000));
    const errorsBeforeDeep = await page.evaluate(() => window.__raypc.errors.length);
    await page.setInputFiles('#pvImport', deep);
    await page.waitForFunction((n) => window.__raypc.errors.length > n, errorsBeforeDeep, { timeout: 5000 });
    const deepError = await page.textContent('#error');
    check(/RGBPoints/.test(deepError) && deepError.length < 300, `deeply nested ParaView file: ${deepError.slice(0, 300)}`);

    // Reversed.
    await page.check('#colorReversed');
    await waitConverged(page);
    check((await rState(page)).color.reversed === true, 'reversed not in the state');
    const dRev = meanAbsDiff(await viewPixels(page), recolored);
    check(dRev > 0.3, `reversing the colours hardly changed the image (${dRev.toFixed(2)})`);
    console.log(`  image change: recoloured ${dColor.toFixed(2)}, imported vs exported ${dImport.toFixed(2)}, reversed ${dRev.toFixed(2)}`);
  },

  // Brush values: a brush's min and max are written at its ends on the axis and can be typed
  // exactly in the Selection panel (the state and the frame get them); × clears one axis, Escape all.
  async brush_values({ context, url }) {
    const page = await openUi(context, url);
    await standardView(page);
    // Depth grows downwards: its smallest tick is at the top (smallest y), latitude the other way.
    const ticks = await page.evaluate(() => Object.fromEntries([...document.querySelectorAll('#parcoords g.dimension')]
      .filter((g) => g.__data__ === 'depth' || g.__data__ === 'lat')
      .map((g) => [g.__data__, [...g.querySelectorAll('.tick')].map((t) => [t.__data__, t.getBoundingClientRect().y]).sort((a, b) => a[0] - b[0])])));
    const topOf = (name) => { const t = ticks[name]; return t[0][1] < t[t.length - 1][1]; };
    check(ticks.depth?.length > 1 && ticks.lat?.length > 1 && topOf('depth') && !topOf('lat'), `depth ticks (value, y) ${JSON.stringify(ticks.depth)}, lat ${JSON.stringify(ticks.lat)}`);
    await brushAxis(page, 'depth', 0.2, 0.6);
    await brushAxis(page, 'temperature', 0.1, 0.7);
    await waitConverged(page);
    const labels = await page.evaluate(() => [...document.querySelectorAll('#parcoords g.dimension')].map((g) => ({
      name: g.__data__, labels: [...g.querySelectorAll('text.brushLabel')].map((t) => t.textContent) })).filter((x) => x.labels.length));
    check(labels.length === 2 && labels.every((l) => l.labels.length === 2), `brush end labels: ${JSON.stringify(labels)}`);
    await page.fill('.brushRow[data-brush="depth"] input.brushMin', '660');
    await page.fill('.brushRow[data-brush="depth"] input.brushMax', '1000');
    await page.dispatchEvent('.brushRow[data-brush="depth"] input.brushMax', 'change');
    await waitConverged(page);
    const s = await rState(page);
    const depth = s.brushes.find((b) => b.name === 'depth');
    check(depth && depth.min === 660 && depth.max === 1000 && s.brushes.length === 2, `typed depth 660 … 1000 km, state brushes ${JSON.stringify(s.brushes)}`);
    const sent = await page.evaluate(() => { const r = window.__raypc, h = r.headers.at(-1); return r.sentLog.find((e) => e.id === h.id); });
    check(JSON.stringify(sent.brushes) === JSON.stringify(s.brushes), `the frame shown was rendered with ${JSON.stringify(sent.brushes)}`);
    const pc = await page.evaluate(() => window.__raypc.parcoords.brushes().find((b) => b.name === 'depth'));
    check(pc && Math.abs(pc.min - 660) < 1 && Math.abs(pc.max - 1000) < 1, `the depth axis shows ${JSON.stringify(pc)}`);
    await page.click('.brushRow[data-brush="depth"] button.brushClear');
    await waitConverged(page);
    check(JSON.stringify((await rState(page)).brushes.map((b) => b.name)) === '["temperature"]', `after × on depth: ${JSON.stringify((await rState(page)).brushes)}`);
    await page.locator('#view3d').focus();
    await page.keyboard.press('Escape');
    await waitConverged(page);
    check((await rState(page)).brushes.length === 0, 'Escape did not clear the brushes');
  },

  // Two ranges on one axis (parcoord-es multi brushes) select their union: the state holds both, the
  // exact selection shown equals the sum of each range's (they are apart) and what `raypc stats`
  // says for the saved state; each range's ends are labelled and typed per range; × removes one
  // range, a click on the axis clears the axis, and a saved state restores both ranges.
  async multi_brush({ context, url, tmp, raypc, dataset }) {
    const page = await openUi(context, url);
    await standardView(page);
    await brushAxis(page, 'depth', 0.05, 0.3);
    await brushAxis(page, 'depth', 0.6, 0.85);
    await waitConverged(page);
    const s = await rState(page);
    const depth = s.brushes.filter((b) => b.name === 'depth');
    check(s.brushes.length === 2 && depth.length === 2, `state.brushes after two drags on depth: ${JSON.stringify(s.brushes)}`);
    const [a, b] = [...depth].sort((x, y) => x.min - y.min);
    check(a.min >= 0 && a.max < b.min && b.max - b.min > 300 && a.max - a.min > 300,
      `two separate depth ranges expected (dragged 5-30 % and 60-85 % of the axis): ${JSON.stringify(depth)}`);
    const labels = await page.evaluate(() => [...document.querySelectorAll('#parcoords g.dimension')]
      .filter((g) => g.__data__ === 'depth').flatMap((g) => [...g.querySelectorAll('text.brushLabel')].map((t) => t.textContent)));
    check(labels.length === 4, `each range's ends labelled on the depth axis: ${JSON.stringify(labels)}`);

    const sel = await page.evaluate(() => window.__raypc.selection);
    const server = await postJson(url + 'api/selection', s);
    check(server.status === 200 && Math.abs(server.body.fractionOfMantle - sel.fractionOfMantle) < 1e-9,
      `UI shows ${JSON.stringify(sel)}, POST /api/selection says ${JSON.stringify(server.body)}`);
    const only = async (r) => (await postJson(url + 'api/selection', { ...s, brushes: [r] })).body.fractionOfMantle;
    const fa = await only(a), fb = await only(b);
    check(fa > 0 && fb > 0 && Math.abs(sel.fractionOfMantle - (fa + fb)) < 1e-9,
      `the union selects ${sel.fractionOfMantle}, the ranges alone ${fa} + ${fb}`);
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#save')]);
    const file = join(tmp, 'multi.json');
    await download.saveAs(file);
    const cli = spawnSync(raypc, ['stats', dataset, '--state', file, '-o', join(tmp, 'multi.csv'), '--quiet'], { encoding: 'utf8', timeout: 60000 });
    check(cli.status === 0, `raypc stats --state refused the saved state: ${cli.stderr}`);
    const row = readFileSync(join(tmp, 'multi.csv'), 'utf8').trim().split('\n').slice(1).map((l) => l.split(',')).find((r) => Number(r[0]) === s.step);
    check(row && Math.abs(Number(row[3]) - 100 * sel.fractionOfMantle) < 1e-4,
      `raypc stats says ${row?.[3]} % at step ${s.step}, the UI ${100 * sel.fractionOfMantle} %`);

    // Typed values change one range only.
    const second = s.brushes.findIndex((x) => x === depth[1] || (x.name === 'depth' && x.min === depth[1].min));
    const typedRow = page.locator('.brushRow').nth(second);
    await typedRow.locator('input.brushMin').fill('1500');
    await typedRow.locator('input.brushMax').fill('2000');
    await typedRow.locator('input.brushMax').dispatchEvent('change');
    await waitConverged(page);
    const typed = (await rState(page)).brushes;
    check(typed.length === 2 && typed[second].min === 1500 && typed[second].max === 2000 &&
      typed[1 - second].min === s.brushes[1 - second].min, `typed 1500 … 2000 into range ${second}: ${JSON.stringify(typed)}`);
    const shown = await page.evaluate(() => window.__raypc.parcoords.brushes());
    check(shown.length === 2 && shown.some((x) => Math.abs(x.min - 1500) < 1 && Math.abs(x.max - 2000) < 1),
      `the depth axis shows ${JSON.stringify(shown)} after typing`);

    // The saved state restores both ranges on the axis.
    await page.goto(url);
    await waitConverged(page);
    const sentBefore = await page.evaluate(() => window.__raypc.lastSentId);
    await page.setInputFiles('#load', file);
    await page.waitForFunction((n) => window.__raypc.lastSentId > n, sentBefore, { timeout: 5000 });
    await waitConverged(page);
    const loaded = await page.evaluate(() => window.__raypc.parcoords.brushes());
    check(loaded.length === 2 && loaded.every((x) => x.name === 'depth') &&
      loaded.every((x) => depth.some((d) => Math.abs(d.min - x.min) < 1e-3 * (d.max - d.min) + 1e-6)),
      `parallel coordinates show ${JSON.stringify(loaded)} after loading ${JSON.stringify(depth)}`);
    // A third range can be drawn beside the loaded ones.
    await brushAxis(page, 'depth', 0.4, 0.5);
    await waitConverged(page);
    check((await rState(page)).brushes.length === 3, `a third range beside two loaded ones: ${JSON.stringify((await rState(page)).brushes)}`);

    await page.locator('.brushRow').nth(0).locator('button.brushClear').click();
    await waitConverged(page);
    check((await rState(page)).brushes.length === 2, `× removes one range: ${JSON.stringify((await rState(page)).brushes)}`);
    // A click on the axis outside its brushes clears the axis.
    const box = await axisBox(page, 'depth');
    const left = await page.evaluate(() => window.__raypc.parcoords.brushes());
    check(left.length === 2, `the depth axis shows ${JSON.stringify(left)} after × on one of three ranges`);
    await page.mouse.click(box.x + box.width / 2, box.y + box.height * 0.98);
    await waitConverged(page);
    check((await rState(page)).brushes.length === 0, `a click on the depth axis left ${JSON.stringify((await rState(page)).brushes)}`);
  },

  // The axes shown and their order are in the state: hiding, showing and dragging axes changes
  // state.axes, and a saved file and the page URL restore the same axes in the same order.
  async axes({ context, url, tmp }) {
    const page = await openUi(context, url);
    await standardView(page);
    const shownOrder = (p) => p.evaluate(() => window.__raypc.parcoords.order());
    const initial = await shownOrder(page);
    check((await rState(page)).axes === null && initial.includes('lat') && !initial.includes('radius'),
      `default: state.axes ${JSON.stringify((await rState(page)).axes)}, shown ${JSON.stringify(initial)}`);
    await page.click('#axisMenu summary');
    await page.check('#axisChoice input[data-axis="radius"]');
    await page.uncheck('#axisChoice input[data-axis="lat"]');
    await page.click('#axisMenu summary');
    // Drag the depth axis by its title to the right end.
    const title = await page.evaluate(() => {
      const g = [...document.querySelectorAll('#parcoords svg g.dimension')].find((x) => x.__data__ === 'depth');
      const r = g?.querySelector('text.label')?.getBoundingClientRect();
      return r ? { x: r.x + r.width / 2, y: r.y + r.height / 2 } : null;
    });
    check(title, 'no depth axis title to drag');
    const panel = await page.locator('#parcoords').boundingBox();
    await page.mouse.move(title.x, title.y);
    await page.mouse.down();
    for (let i = 1; i <= 12; i++) await page.mouse.move(title.x + ((panel.x + panel.width - 5 - title.x) * i) / 12, title.y);
    await page.mouse.up();
    await page.waitForFunction(() => {
      const a = window.__raypc.state().axes;
      return Array.isArray(a) && a[a.length - 1] === 'depth';
    }, null, { timeout: 5000 }).catch(() => {});
    const s = await rState(page);
    const order = await shownOrder(page);
    check(Array.isArray(s.axes) && JSON.stringify(s.axes) === JSON.stringify(order) && order.at(-1) === 'depth' &&
      order.includes('radius') && !order.includes('lat'),
      `after showing radius, hiding lat and dragging depth to the right: state.axes ${JSON.stringify(s.axes)}, shown ${JSON.stringify(order)}`);
    check(JSON.stringify(order) !== JSON.stringify(initial), 'the axes did not change; the test would prove nothing');
    // Brushes still land on the axis they are drawn on once axes have moved (parcoord-es's multi
    // mode names brush elements by axis position).
    await brushAxis(page, 'depth', 0.1, 0.3);
    await brushAxis(page, 'depth', 0.6, 0.8);
    await brushAxis(page, 'temperature', 0.2, 0.6);
    await waitConverged(page);
    const moved = await page.evaluate(() => ({ state: window.__raypc.state().brushes, shown: window.__raypc.parcoords.brushes() }));
    const names = (list) => list.map((x) => x.name).sort().join(',');
    check(names(moved.state) === 'depth,depth,temperature' && names(moved.shown) === names(moved.state),
      `brushes after moving axes: state ${JSON.stringify(moved.state)}, shown ${JSON.stringify(moved.shown)}`);
    await page.keyboard.press('Escape');
    await waitConverged(page);

    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#save')]);
    const file = join(tmp, 'axes.json');
    await download.saveAs(file);
    check(JSON.stringify(JSON.parse(readFileSync(file, 'utf8')).axes) === JSON.stringify(order), 'the saved file lacks the axes');
    const hash = new URL(page.url()).hash;

    await page.goto(url);
    await waitConverged(page);
    check(JSON.stringify(await shownOrder(page)) === JSON.stringify(initial), 'a fresh page does not show the default axes');
    const sentBefore = await page.evaluate(() => window.__raypc.lastSentId);
    await page.setInputFiles('#load', file);
    await page.waitForFunction((n) => window.__raypc.lastSentId > n, sentBefore, { timeout: 5000 });
    await page.waitForFunction((o) => JSON.stringify(window.__raypc.parcoords.order()) === o, JSON.stringify(order), { timeout: 5000 })
      .catch(() => {});
    const loaded = await shownOrder(page);
    check(JSON.stringify(loaded) === JSON.stringify(order), `after loading the file the axes are ${JSON.stringify(loaded)}, saved ${JSON.stringify(order)}`);
    const ticks = await page.evaluate(() => Object.fromEntries([...document.querySelectorAll('#axisChoice input')].map((i) => [i.dataset.axis, i.checked])));
    check(ticks.radius === true && ticks.lat === false, `the Axes menu after loading: ${JSON.stringify(ticks)}`);

    const page2 = await openUi(context, url, { hash });
    await page2.waitForFunction((o) => JSON.stringify(window.__raypc.parcoords.order()) === o, JSON.stringify(order), { timeout: 5000 })
      .catch(() => {});
    const fromUrl = await shownOrder(page2);
    check(JSON.stringify(fromUrl) === JSON.stringify(order), `the shared URL shows the axes ${JSON.stringify(fromUrl)}, saved ${JSON.stringify(order)}`);
  },

  // Camera: the wheel cannot take the eye inside the planet (unless Fly inside is ticked); arrow
  // keys orbit and + zooms; a double-click resets the view.
  async camera({ context, url }) {
    const page = await openUi(context, url);
    const eye = () => page.evaluate(() => {
      const c = window.__raypc.state().camera, el = (c.elevationDeg * Math.PI) / 180, az = (c.azimuthDeg * Math.PI) / 180;
      const o = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
      return Math.hypot(...c.targetKm.map((t, k) => t + o[k] * c.distanceKm));
    });
    const r = await page.locator('#view3d').boundingBox();
    await page.mouse.move(r.x + r.width / 2, r.y + r.height / 2);
    for (let i = 0; i < 20; i++) await page.mouse.wheel(0, -400);
    await page.waitForTimeout(400);
    await waitConverged(page);
    const inside = await eye();
    check(inside >= 6371, `after 20 wheel steps the eye is ${inside.toFixed(0)} km from the centre, inside the planet`);
    await page.check('#flyInside');
    await page.mouse.move(r.x + r.width / 2, r.y + r.height / 2); // checking the box moved the mouse away
    for (let i = 0; i < 20; i++) await page.mouse.wheel(0, -400);
    await page.waitForTimeout(400);
    await waitConverged(page);
    const flown = await eye();
    check(flown < 6371, `with Fly inside the eye stays at ${flown.toFixed(0)} km`);
    await page.uncheck('#flyInside');
    const def = (await info(url)).defaultState.camera;
    await page.mouse.dblclick(r.x + r.width / 2, r.y + r.height / 2);
    await waitConverged(page);
    check(JSON.stringify((await rState(page)).camera) === JSON.stringify(def), `double-click did not reset the camera: ${JSON.stringify((await rState(page)).camera)}`);
    await page.locator('#view3d').focus();
    await page.keyboard.press('ArrowLeft');
    await page.keyboard.press('+');
    await page.waitForTimeout(400);
    await waitConverged(page);
    const c = (await rState(page)).camera;
    check(c.azimuthDeg !== def.azimuthDeg && c.distanceKm < def.distanceKm, `keys: azimuth ${def.azimuthDeg} -> ${c.azimuthDeg}, distance ${def.distanceKm} -> ${c.distanceKm}`);
  },

  // Responsiveness with 100 000 lines: the page answers a click while the lines are still being
  // drawn — right after the sample arrived and right after a brush release (run with GPU
  // rasterisation on by ctest's browser.gpu.responsive, where it used to stall for minutes).
  async responsive({ context, url }) {
    const t0 = Date.now();
    const page = await openUi(context, url, { timeoutMs: 60000 });
    await page.waitForFunction(() => window.__raypc.sampleStep >= 0, null, { timeout: 60000 });
    const rows = await page.evaluate(() => window.__raypc.parcoords.rowCount);
    check(rows >= 50000, `the sample has ${rows} rows, expected the 100 000 asked for (at least 50 000)`);
    // Each click: when the first frame after the page handled it was painted (ms since the epoch,
    // as the test's own clock, which says when the click was sent: a page whose main thread is busy
    // gives its input events a late timeStamp).
    await page.evaluate(() => {
      window.addEventListener('click', () => {
        requestAnimationFrame(() => { window.__click = { painted: performance.timeOrigin + performance.now() }; });
      }, true);
    });
    // A click sent while a layer's lines are still being drawn must be answered before the last of
    // them is drawn: a page that drew them in one task could answer only after it. (Not a time
    // limit: on a loaded machine both take longer, the order stays.) `start` begins a drawing; a
    // try whose lines were all drawn before the click was sent says nothing, and is made again (on a
    // quiet machine with GPU rasterisation a drawing can end within the test's own round trips).
    const clickWhileDrawing = async (layer, start) => {
      let last = null;
      for (let attempt = 1; attempt <= 5; attempt++) {
        await start(attempt);
        await page.waitForFunction((l) => window.__raypc.parcoords.timing.drawnAt[l] === 0, layer, { timeout: 3000, polling: 10 }).catch(() => {});
        const before = await page.evaluate(() => window.__raypc.state().legend);
        await page.locator('#legend').scrollIntoViewIfNeeded();
        const box = await page.locator('#legend').boundingBox();
        await page.evaluate(() => { window.__click = undefined; });
        const sent = Date.now();
        await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
        await page.waitForFunction((b) => window.__raypc.state().legend !== b && window.__click !== undefined, before, { timeout: 30000, polling: 20 });
        await page.waitForFunction((l) => window.__raypc.parcoords.timing.drawnAt[l] > 0, layer, { timeout: 120000, polling: 50 })
          .catch(() => { throw new TestFailure(`the ${layer} lines were not all drawn within 120 s`); });
        const t = await page.evaluate((l) => ({ ...window.__click, drawnAt: performance.timeOrigin + window.__raypc.parcoords.timing.drawnAt[l] }), layer);
        t.sent = sent;
        if (t.sent < t.drawnAt) {
          last = { ms: Math.round(t.painted - t.sent), rest: Math.round(t.drawnAt - t.painted) };
          if (last.rest > 0) return last;
          // Under load a click sent near the end of a drawing may be answered just after it: again,
          // with a new drawing (a page drawing in one task answers every try after it).
          console.log(`  try ${attempt} (${layer}): answered ${-last.rest} ms after the last line, ${last.ms} ms after it was sent`);
        } else {
          console.log(`  try ${attempt} (${layer}): the lines were all drawn ${Math.round(t.sent - t.drawnAt)} ms before the click was sent`);
        }
      }
      return last;
    };
    const atOpen = await clickWhileDrawing('foreground', async (attempt) => {
      // After the first try, a new window size draws every line again.
      if (attempt > 1) await page.setViewportSize({ width: 1280 + 40 * attempt, height: 860 });
    });
    await page.locator('#parcoords').scrollIntoViewIfNeeded();
    // Wide brushes: most of the lines to draw again, so that the drawing lasts.
    const afterBrush = await clickWhileDrawing('brushed', (attempt) => brushAxis(page, 'temperature', 0.1 + 0.02 * attempt, 0.9 + 0.02 * attempt));
    const text = (r) => (r ? `in ${r.ms} ms, ${r.rest} ms before the last line` : 'never while they were drawn');
    console.log(`  ${rows} lines; opened in ${Date.now() - t0} ms; a click answered ${text(atOpen)} (all lines), ${text(afterBrush)} (after a brush release)`);
    // A page that draws in one task also answers the test's own calls (state, box of the button)
    // only after the lines: then no click is ever sent while they are drawn.
    check(afterBrush !== null, 'in 5 brushes no click could be sent before the brushed lines were all drawn: the page was busy throughout (or drew them at once)');
    check((atOpen === null || atOpen.rest > 0) && afterBrush.rest > 0,
      `a click was answered only after the lines were drawn: ${text(atOpen)} (all lines), ${text(afterBrush)} (after a brush release)`);
  },

  // Pathlines: showing them changes the image; the second parallel-coordinates plot holds one line
  // per pathline of the window; brushing its length axis sets state.pathlines.filters, lowers the
  // visible-line count and changes the image.
  async pathlines({ context, url }) {
    const ds = await info(url);
    check(ds.defaultState.version >= 2 && ds.defaultState.pathlines, `the server's default state has no pathlines (version ${ds.defaultState.version})`);
    const page = await openUi(context, url);
    await standardView(page);
    // Last step: the window holds the lines of every step; no volume brushes. The fixture's lines
    // are short (slow flow), so: a transparent volume, no core, thick tubes set in the UI.
    await page.evaluate((n) => {
      const s = window.__raypc.state();
      window.__raypc.setState({ ...s, step: n - 1, core: { ...s.core, visible: false }, color: { ...s.color, opacity: [[0, 0], [1, 0]] } });
    }, ds.steps.length);
    await waitConverged(page);
    await page.fill('#plMinWidth', '0');
    await page.dispatchEvent('#plMinWidth', 'change');
    await page.fill('#plRadius', '250');
    await page.dispatchEvent('#plRadius', 'change');
    await waitConverged(page);
    check((await rState(page)).pathlines.radiusKm === 250, `tube radius from the UI: ${JSON.stringify((await rState(page)).pathlines)}`);
    const off = await viewPixels(page);
    await page.check('#plVisible');
    await waitConverged(page);
    await page.waitForFunction(() => window.__raypc.pathlines && window.__raypc.pathlines.lines > 0, null, { timeout: 20000 })
      .catch(() => { throw new TestFailure('no pathline attributes arrived'); });
    const sOn = await rState(page);
    check(sOn.pathlines.visible === true, `state.pathlines after showing: ${JSON.stringify(sOn.pathlines)}`);
    const on = await viewPixels(page);
    const dOn = meanAbsDiff(off, on);
    check(dOn > 0.3, `showing the pathlines hardly changed the image (${dOn.toFixed(2)})`);
    const pl0 = await page.evaluate(() => window.__raypc.pathlines);
    check(pl0.visibleLines === pl0.lines, `with no filters ${pl0.visibleLines} of ${pl0.lines} lines counted`);
    check((await page.textContent('#plCount')).includes(`${pl0.lines.toLocaleString('en-US')} of`), `count text '${await page.textContent('#plCount')}'`);
    await page.waitForFunction(() => document.querySelectorAll('#plParcoords svg g.dimension').length > 5, null, { timeout: 10000 })
      .catch(() => { throw new TestFailure('the pathline parallel coordinates did not appear'); });

    const b = await page.evaluate(() => {
      for (const g of document.querySelectorAll('#plParcoords svg g.dimension')) {
        if (g.__data__ !== 'length') continue;
        const r = g.querySelector('.brush .overlay')?.getBoundingClientRect();
        if (r) return { x: r.x, y: r.y, width: r.width, height: r.height };
      }
      return null;
    });
    check(b, 'no brushable length axis in the pathline parallel coordinates');
    const x = b.x + b.width / 2;
    await page.mouse.move(x, b.y + b.height * 0.02);
    await page.mouse.down();
    for (let i = 1; i <= 8; i++) await page.mouse.move(x, b.y + b.height * (0.02 + (0.6 * i) / 8));
    await page.mouse.up();
    await waitConverged(page);
    const sF = await rState(page);
    check(sF.pathlines.filters.length === 1 && sF.pathlines.filters[0].name === 'length', `pathlines.filters after brushing: ${JSON.stringify(sF.pathlines.filters)}`);
    const pl1 = await page.evaluate(() => window.__raypc.pathlines);
    check(pl1.visibleLines < pl0.visibleLines && pl1.visibleLines >= 0, `visible lines ${pl0.visibleLines} -> ${pl1.visibleLines} after brushing the longest 60 %`);
    const header = await page.evaluate(() => { const r = window.__raypc, h = r.headers.at(-1); return h.id === r.lastSentId ? h : null; });
    check(header, 'the frame shown is not of the filtered state');
    check(header.pathlines && header.pathlines.lines === pl0.lines && header.pathlines.visible === pl1.visibleLines,
      `the server shows ${JSON.stringify(header.pathlines)} lines, the UI counts ${pl1.visibleLines} of ${pl0.lines}`);
    const filtered = await viewPixels(page);
    const dF = meanAbsDiff(on, filtered);
    check(dF > 0.1, `filtering lines hardly changed the image (${dF.toFixed(2)})`);

    // Thin tubes (1 km, under a pixel at this distance) are drawn at least the minimum width:
    // 0 px leaves them a hair wide, 6 px widens them.
    const thin = async (px) => {
      await page.fill('#plRadius', '1');
      await page.dispatchEvent('#plRadius', 'change');
      await page.fill('#plMinWidth', String(px));
      await page.dispatchEvent('#plMinWidth', 'change');
      await waitConverged(page);
      check((await rState(page)).pathlines.minWidthPx === px, `pathlines.minWidthPx ${JSON.stringify((await rState(page)).pathlines)}`);
      return viewPixels(page);
    };
    const hair = await thin(0), wide = await thin(6);
    const dW = meanAbsDiff(hair, wide);
    check(dW > 0.05, `a 6 px minimum width hardly changed 1 km tubes (${dW.toFixed(3)})`);
    console.log(`  lines ${pl0.lines} -> ${pl1.visibleLines}; image change on ${dOn.toFixed(2)}, filtered ${dF.toFixed(2)}, minimum width ${dW.toFixed(3)}`);

    // The UI parses the pathlines object as strictly as the server: an unknown key or a wrong type
    // is refused and changes nothing; a version-1 document gets no pathlines.
    const refused = await page.evaluate(() => {
      const s = window.__raypc.state(), out = [];
      for (const bad of [{ ...s, pathlines: { ...s.pathlines, bogus: 1 } }, { ...s, pathlines: { ...s.pathlines, visible: 'yes' } },
        { ...s, version: 1 }]) {
        try { window.__raypc.setState(bad); out.push(null); } catch (e) { out.push(e.message); }
      }
      return { out, same: JSON.stringify(window.__raypc.state()) === JSON.stringify(s) };
    });
    check(/pathlines\.bogus: unknown key/.test(refused.out[0]) && /pathlines\.visible/.test(refused.out[1]) &&
      /version 1/.test(refused.out[2]) && refused.same, `strict pathlines parsing: ${JSON.stringify(refused)}`);
  },

  // The distributed server (docs/scaling.md), started under mpirun with 2 ranks: the UI works as
  // alone — converged frames come, each says it was rendered by 2 ranks (the frame header and the
  // status line), and a brush sent from the UI changes the picture.
  async distributed({ context, url }) {
    const page = await openUi(context, url);
    await standardView(page);
    const ranks = await page.evaluate(() => window.__raypc.headers.map((h) => h.ranks));
    check(ranks.length > 0 && ranks.every((r) => r === 2), `frame headers' ranks under 2 MPI ranks: ${JSON.stringify(ranks)}`);
    const status = await page.textContent('#status');
    check(/\b2 ranks\b/.test(status), `the status line does not say '2 ranks': ${status}`);
    const before = await viewPixels(page);
    const ds = await info(url);
    const radius = ds.coordinates.find((c) => c.name === 'radius');
    await page.evaluate((r) => {
      const s = window.__raypc.state();
      window.__raypc.setState({ ...s, brushes: [{ name: 'radius', min: r.min + 0.6 * (r.max - r.min), max: r.max }] });
    }, radius);
    await waitConverged(page);
    const after = await viewPixels(page);
    const diff = meanAbsDiff(before, after);
    check(diff > 2, `brushing the outer 40 % of the radius changed the picture by only ${diff.toFixed(2)} grey levels`);
    const last = await page.evaluate(() => window.__raypc.headers.at(-1));
    check(last.ranks === 2 && last.converged, `last frame: ${JSON.stringify(last)}`);
  },

  // netCDF files served at once (`raypc serve FILE.nc…`): while the series is held back after its
  // step 0 (RAYPC_TEST_HOLD_SERIES), the UI shows step 0 alone and the header says the series is being
  // preprocessed; once it is done, the page reloads by itself onto all 3 steps and keeps the view
  // (the state is in the URL).
  async series({ context, url, tmp }) {
    const page = await openUi(context, url);
    await page.waitForSelector('#seriesProgress:not([hidden])', { timeout: 10000 })
      .catch(() => { throw new TestFailure('the header shows no progress of the series while step 0 is served alone'); });
    const text = await page.textContent('#seriesProgress');
    check(/^Showing step 0 while the series is preprocessed: step 1 of 3 done( · about \d+ s left)?$/.test(text), `progress while held: '${text}'`);
    const label = await page.textContent('#stepLabel');
    check(/of 0–0\b/.test(label), `the step label while only step 0 is served: '${label}'`);
    await page.evaluate(() => {
      const s = window.__raypc.state();
      window.__raypc.setState({ ...s, camera: { ...s.camera, azimuthDeg: 123 } });
    });
    await waitConverged(page);
    const reloaded = page.waitForEvent('load', { timeout: 60000 });
    writeFileSync(join(tmp, 'go'), '');
    await reloaded.catch(() => { throw new TestFailure('the page did not reload within 60 s of the series being released'); });
    await page.waitForFunction(() => window.__raypc && window.__raypc.headers.length > 0, null, { timeout: 30000 });
    await waitConverged(page);
    const after = await page.textContent('#stepLabel');
    check(/of 0–2\b/.test(after), `the step label after the reload: '${after}'`);
    check(await page.isHidden('#seriesProgress'), 'the progress stays in the header after the whole series is served');
    const azimuth = await page.evaluate(() => window.__raypc.state().camera.azimuthDeg);
    check(azimuth === 123, `the view after the reload has azimuth ${azimuth}, not the 123 set before`);
  },

  // A model that is not the contest's (ASPECT's output, deal.II's files in
  // tests/data/aspect-layout/shell-amr, resampled): the first view colours the temperature anomaly
  // derived from T and shows the blobs; presets naming variables the dataset lacks are greyed with
  // the server's reason, the others apply.
  async aspect({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const state = await rState(page);
    check(state.color.variable === 'temperature anomaly', `the first view colours '${state.color.variable}', not the derived temperature anomaly`);
    const coloured = await page.evaluate(() => {
      const { data: d } = window.__viewImageData();
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - d[i + 2]) > 40) n++;
      return n;
    });
    check(coloured > 200, `the first view shows ${coloured} red or blue pixels: no anomaly visible`);
    const presets = await (await fetch(url + 'api/presets')).json();
    const unavailable = presets.filter((p) => p.unavailable);
    check(unavailable.length > 0 && unavailable.length < presets.length,
      `${unavailable.length} of ${presets.length} presets unavailable; expected the expansivity and density ones only`);
    for (const p of unavailable)
      check(/unknown/.test(p.unavailable) && /thermal expansivity anomaly|spin transition|'temperature'/.test(p.unavailable),
        `${p.name}: reason '${p.unavailable}'`);
    const buttons = await page.evaluate(() => [...document.querySelectorAll('#presets button')].map((b) => ({ name: b.dataset.preset, disabled: b.disabled, title: b.title })));
    for (const p of presets) {
      const b = buttons.find((x) => x.name === p.name);
      check(b && b.disabled === Boolean(p.unavailable), `${p.name}: button ${b?.disabled ? 'disabled' : 'enabled'}, the server says ${p.unavailable ?? 'usable'}`);
      if (p.unavailable) check(b.title.includes(p.unavailable), `${p.name}: the button's tooltip '${b.title}' does not give the reason`);
    }
    const note = await page.textContent('#presetNote');
    check(note.includes(`${unavailable.length} of ${presets.length} presets are not for this dataset`), `preset note '${note}'`);
    // A usable preset (cold slabs at 660 km: temperature anomaly and depth) applies without error.
    const usable = presets.find((p) => p.name === 'task1-slabs-660km' && !p.unavailable);
    check(usable, 'task1-slabs-660km is unavailable on a model with a temperature anomaly');
    const sentBefore = await page.evaluate(() => window.__raypc.lastSentId);
    await page.click('#presets button[data-preset="task1-slabs-660km"]');
    await page.waitForFunction((n) => window.__raypc.lastSentId > n, sentBefore, { timeout: 5000 })
      .catch(() => { throw new TestFailure('clicking task1-slabs-660km sent no state'); });
    await waitConverged(page);
    const errors = await page.evaluate(() => window.__raypc.errors);
    check(errors.length === 0, `errors after the preset: ${JSON.stringify(errors)}`);
    // A greyed button does nothing when clicked.
    const sent = await page.evaluate(() => window.__raypc.lastSentId);
    await page.click(`#presets button[data-preset="${unavailable[0].name}"]`, { force: true }).catch(() => {});
    await page.waitForTimeout(300);
    check(await page.evaluate(() => window.__raypc.lastSentId) === sent, 'a greyed preset sent a state');
  },

  // A seismic tomography model (tests/data/emc-layout: one variable vs in km/s, no velocity, no
  // temperature): the UI opens on what is there. The first view colours vs's anomaly to its shell
  // means (computed when read) on a diverging map, the parallel coordinates have vs's axis and
  // brushing it selects, every preset says why it does not apply, and nothing reports an error.
  async tomography({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const state = await rState(page);
    check(state.color.variable === 'vs anomaly', `the first view colours '${state.color.variable}', not vs anomaly`);
    check(state.color.colorMap === 'blue-white-red', `the first view of an anomaly uses '${state.color.colorMap}', not blue-white-red`);
    const lit = await litPixels(page);
    check(lit > 1000, `the first view shows ${lit} lit pixels: the model is not drawn`);
    const presets = await (await fetch(url + 'api/presets')).json();
    check(presets.length > 0 && presets.every((p) => p.unavailable && /the dataset has: vs/.test(p.unavailable)),
      `presets on a vs model: ${JSON.stringify(presets.map((p) => [p.name, p.unavailable]))}`);
    const note = await page.textContent('#presetNote');
    check(note.includes(`${presets.length} of ${presets.length} presets are not for this dataset`), `preset note '${note}'`);
    await brushAxis(page, 'vs', 0.1, 0.4);
    await waitConverged(page);
    const brushed = await rState(page);
    check(brushed.brushes.length === 1 && brushed.brushes[0].name === 'vs',
      `the brush on the vs axis: ${JSON.stringify(brushed.brushes)}`);
    const noPathlines = await page.textContent('#plUnavailable');
    check(await page.isVisible('#plUnavailable') && noPathlines.includes('the model has no velocity'),
      `the Pathlines panel on a model without a flow says '${noPathlines}'`);
    const errors = await page.evaluate(() => window.__raypc.errors);
    check(errors.length === 0, `errors on a tomography model: ${JSON.stringify(errors)}`);
  },

  // A regional tomography model with a hole (tests/data/emc-layout/regional_vs.nc: lat 20..55, lon
  // -130..-65, no data east of -100 below 400 km): the first view faces the region and draws it, the
  // parallel coordinates draw no line of a missing value, a brush on vs selects a share of the region
  // (as POST /api/selection computes it), and nothing reports an error.
  async regional({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const state = await rState(page);
    check(Math.abs(state.camera.azimuthDeg - 262.5) < 1e-6 && Math.abs(state.camera.elevationDeg - 37.5) < 1e-6,
      `the first view looks at azimuth ${state.camera.azimuthDeg}, elevation ${state.camera.elevationDeg}, not the region's centre (262.5, 37.5)`);
    const lit = await litPixels(page);
    check(lit > 1000, `the first view shows ${lit} lit pixels: the region is not drawn`);
    await brushAxis(page, 'vs', 0.05, 0.95);
    await waitConverged(page);
    await page.waitForFunction(() => window.__raypc.selection && Number.isFinite(window.__raypc.selection.fractionOfMantle),
      null, { timeout: 30000 });
    const brushed = await rState(page);
    const sel = await page.evaluate(() => window.__raypc.selection);
    const server = await postJson(url + 'api/selection', brushed);
    check(server.status === 200 && Math.abs(server.body.fractionOfMantle - sel.fractionOfMantle) < 1e-9,
      `UI shows ${sel.fractionOfMantle}, POST /api/selection says ${JSON.stringify(server.body)}`);
    check(sel.fractionOfMantle > 0.05 && sel.fractionOfMantle < 0.76,
      `a brush over most of vs selects ${sel.fractionOfMantle} of the region, which has no data in a quarter of it`);
    const errors = await page.evaluate(() => window.__raypc.errors);
    check(errors.length === 0, `errors on a regional model: ${JSON.stringify(errors)}`);
  },

  // A CitcomS run (tests/data/citcoms-layout: 12 caps, HDF5, resampled): the first view colours the
  // temperature anomaly computed from its temperature and draws it, the parallel coordinates have
  // its axes, and nothing reports an error.
  async citcoms({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const state = await rState(page);
    check(state.color.variable === 'temperature anomaly', `the first view colours '${state.color.variable}', not the temperature anomaly`);
    const lit = await litPixels(page);
    check(lit > 1000, `the first view shows ${lit} lit pixels: the run is not drawn`);
    await brushAxis(page, 'viscosity', 0.1, 0.5);
    await waitConverged(page);
    const brushed = await rState(page);
    check(brushed.brushes.length === 1 && brushed.brushes[0].name === 'viscosity',
      `the brush on the viscosity axis: ${JSON.stringify(brushed.brushes)}`);
    const errors = await page.evaluate(() => window.__raypc.errors);
    check(errors.length === 0, `errors on a CitcomS run: ${JSON.stringify(errors)}`);
  },

  // The UI linked both ways (docs/protocol.md, GET/POST /api/link): a state a program sets
  // is applied by the open page as a loaded file is, with a note; what the user then brushes is the
  // linked state a program reads, from the UI, at a higher version.
  async link({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const linkOf = async () => (await fetch(url + 'api/link')).json();
    // Object keys in one order: the server writes them sorted.
    const canonical = (v) => JSON.stringify(v, (k, x) => (x && typeof x === 'object' && !Array.isArray(x)
      ? Object.fromEntries(Object.keys(x).sort().map((key) => [key, x[key]])) : x));
    const start = await linkOf();
    check(start.sessions === 1 && start.source === 'ui', `/api/link with the page open: ${JSON.stringify(start)}`);

    const { image: _image, ...doc } = await rState(page);
    const viewImage = (await rState(page)).image;
    const set = await postJson(url + 'api/link', { state: { ...doc, brushes: [{ name: 'depth', min: 560, max: 760 }] } });
    check(set.status === 200 && set.body.sessions === 1 && set.body.version === start.version + 1,
      `POST /api/link: ${set.status} ${JSON.stringify(set.body)} (before: version ${start.version})`);
    await page.waitForFunction(() => /loaded the linked state/.test(document.getElementById('status').textContent), null, { timeout: 10000 })
      .catch(async () => { throw new TestFailure(`no note of the linked state; status '${await page.textContent('#status')}'`); });
    const linked = await rState(page);
    check(canonical(linked.brushes) === canonical([{ name: 'depth', min: 560, max: 760 }]),
      `the page's brushes after POST /api/link: ${JSON.stringify(linked.brushes)}`);
    check(linked.image.width === viewImage.width && linked.image.height === viewImage.height,
      `a linked state without an image size renders at ${linked.image.width}x${linked.image.height}, the view is ${viewImage.width}x${viewImage.height}`);
    await waitConverged(page);

    // A state the server refuses is not pushed and changes nothing.
    const bad = await postJson(url + 'api/link', { state: { ...doc, brushes: [{ name: 'pressure', min: 0, max: 1 }] } });
    check(bad.status === 400 && /pressure/.test(bad.body.error), `POST /api/link of an unknown variable: ${bad.status} ${JSON.stringify(bad.body)}`);

    // (The parallel coordinates redraw the depth brush from the axis and may give it back a rounding
    // off, e.g. 560.0000000000001.)
    await brushAxis(page, 'temperature', 0.1, 0.4);
    await waitConverged(page);
    const shown = await rState(page);
    check(shown.brushes.some((b) => b.name === 'temperature') && shown.brushes.some((b) => b.name === 'depth' && Math.abs(b.min - 560) < 1e-6 && Math.abs(b.max - 760) < 1e-6),
      `the page's brushes after brushing temperature: ${JSON.stringify(shown.brushes)}`);
    let read = await linkOf();
    for (let i = 0; i < 50 && canonical(read.state) !== canonical(shown); i++) {
      await page.waitForTimeout(100);
      read = await linkOf();
    }
    check(read.source === 'ui' && read.version > set.body.version,
      `/api/link after brushing: source ${read.source}, version ${read.version} (POST gave ${set.body.version})`);
    check(canonical(read.state) === canonical(shown), `/api/link's state is not the page's:\n${canonical(read.state)}\n${canonical(shown)}`);
    const errors = await page.evaluate(() => window.__raypc.errors);
    check(errors.length === 0, `errors in the page: ${JSON.stringify(errors)}`);
  },

  // The first view at 1920x1080 frames the mantle (measured in pixels of
  // the picture: the 410 km ring spans most of the view's height), shows the legend with the
  // variable and the shells' key with each depth, draws the 410 and 660 km rings in colours of
  // their own (the key's), and a preset that switches the colour variable says so on the view.
  async first_view({ context, url, dataset }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    // The header names the dataset (/api/info's name: its directory's last two path components).
    const name = `${basename(dirname(dataset))}/${basename(dataset)}`;
    const header = await page.textContent('#dataset');
    check(header.startsWith(`${name} · `), `the header says '${header}': expected the dataset's name ${name} first`);
    check((await page.title()) === `RayPC · ${name}`, `the page's title '${await page.title()}' does not name ${name}`);
    const s = await rState(page);
    // The shells' colours as the server drew them (the frame header's key, the UI's legend).
    const shellKey = await page.evaluate(() => window.__raypc.headers.at(-1).shellKey ?? []);
    check(shellKey.length === 2, `the frame header's shell key ${JSON.stringify(shellKey)}: expected 410 and 660 km`);
    // The view's picture at full resolution: the extent of what is drawn (any channel > 40) and
    // the pixels in each shell's colour.
    const measure = () => page.evaluate((palette) => {
      const { data: d, width, height } = window.__viewImageData();
      let top = height, bottom = -1, left = width, right = -1;
      const near = palette.map(() => 0);
      for (let y = 0; y < height; y++)
        for (let x = 0; x < width; x++) {
          const o = (y * width + x) * 4;
          const [r, g, b] = [d[o], d[o + 1], d[o + 2]];
          if (Math.max(r, g, b) <= 40) continue;
          top = Math.min(top, y); bottom = Math.max(bottom, y); left = Math.min(left, x); right = Math.max(right, x);
          // Pixels of a shell's hue (its colour at any brightness): the ring and its label.
          const top3 = Math.max(r, g, b);
          palette.forEach(([pr, pg, pb], k) => {
            const pm = Math.max(pr, pg, pb);
            if (Math.abs(r / top3 - pr / pm) < 0.12 && Math.abs(g / top3 - pg / pm) < 0.12 && Math.abs(b / top3 - pb / pm) < 0.12) near[k]++;
          });
        }
      return { width, height, top, bottom, left, right, near };
    }, shellKey.map((k) => k.color));
    const m = await measure();
    const spanY = (m.bottom - m.top + 1) / m.height, spanX = (m.right - m.left + 1) / m.width;
    const centreY = (m.top + m.bottom) / 2 / m.height;
    console.log(`  first view ${m.width}x${m.height}: drawn ${m.right - m.left + 1}x${m.bottom - m.top + 1} px (${(100 * spanX).toFixed(0)} % of the width, ${(100 * spanY).toFixed(0)} % of the height); shell-coloured pixels ${m.near.join(', ')}`);
    check(m.width >= 1200, `the view is ${m.width} px wide at 1920x1080`);
    check(spanY >= 0.8 && Math.abs(centreY - 0.5) < 0.05,
      `the mantle spans ${(100 * spanY).toFixed(0)} % of the view's height, centred at ${(100 * centreY).toFixed(0)} %: expected at least 80 %, centred`);
    // The legend: the variable with its units, and the shells' key naming each depth.
    check(await page.isVisible('#legends'), 'no legend on the first view');
    const titles = await page.evaluate(() => [...document.querySelectorAll('#legends .legendTitle')].map((e) => e.textContent));
    check(titles.length >= 1 && titles[0].startsWith(s.color.variable) && /\[.+\]/.test(titles[0]), `legend titles ${JSON.stringify(titles)} for ${s.color.variable}`);
    const key = await page.textContent('#legends .shellKey').catch(() => '');
    check(s.reference.shells.visible && /410 km/.test(key) && /660 km/.test(key), `shells ${JSON.stringify(s.reference.shells)}, key '${key}'`);
    // The 410 and 660 km rings in their own colours: both hues are on the picture.
    check(m.near[0] > 100 && m.near[1] > 100, `pixels in the 410 km shell's colour: ${m.near[0]}, in the 660 km one's: ${m.near[1]}`);
    await page.uncheck('#refShells');
    await waitConverged(page);
    const off = await measure();
    check(off.near[0] < m.near[0] / 5 && off.near[1] < m.near[1] / 5, `without shells still ${off.near.join(', ')} shell-coloured pixels (with: ${m.near.join(', ')})`);
    check(!(await page.isVisible('#legends .shellKey')), 'the shells\' key stays without shells');

    // A preset that colours by another variable says so on the view.
    check(!(await page.isVisible('#viewNote')), 'a note on the first view');
    const presets = await (await fetch(url + 'api/presets')).json();
    const other = presets.find((p) => !p.unavailable && p.state.color && p.state.color.variable && p.state.color.variable !== s.color.variable);
    check(other, 'no preset colours by another variable');
    await page.click(`#presets button[data-preset="${other.name}"]`);
    await waitConverged(page);
    const note = await page.textContent('#viewNote');
    check(await page.isVisible('#viewNote') && note.includes(`colour now: ${other.state.color.variable}`) && note.includes(other.title),
      `the note on the view after preset ${other.name}: '${note}'`);
    const after = await page.evaluate(() => [...document.querySelectorAll('#legends .legendTitle')].map((e) => e.textContent));
    check(after[0].startsWith(other.state.color.variable), `the legend after preset ${other.name}: ${JSON.stringify(after)}`);
    await page.selectOption('#variable', s.color.variable);
    await page.waitForFunction(() => document.getElementById('viewNote').hidden, null, { timeout: 5000 })
      .catch(() => { throw new TestFailure('choosing a variable left the preset\'s note on the view'); });
  },

  // Issue 47, stalls that answer the question (docs/features.md, "In the UI"): the stall measure a
  // selection implies when none was chosen (cold → the tip, hot → the head, else the mean depth),
  // said in the panel and sent with the request; a warning when the selection brushes depth; every
  // stall cell with its units on one line and no zero-length stall; the legend names the track id
  // the table names.
  async stalls({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    // A document with these brushes that names no stall measure (as the presets): the page picks one.
    const setBrushes = (b) => page.evaluate((brushes) => {
      const s = window.__raypc.state();
      const { stallBy: _, ...features } = s.features;
      window.__raypc.setState({ ...s, step: 0, brushes, features });
    }, b);
    // Waits for an answer to a request asked after `n` answers, and returns it with the state then.
    const answerAfter = async (n, what) => {
      await page.waitForFunction((k) => window.__raypc.featureAnswers.length > k && window.__raypc.featureAnswers.at(-1), n, { timeout: 30000 })
        .catch(async () => { throw new TestFailure(`${what}: no features; note: ${await page.textContent('#featuresNote')}; errors: ${await page.evaluate(() => window.__raypc.errors.join('; '))}`); });
      return page.evaluate(() => ({ f: window.__raypc.featureAnswers.at(-1), state: window.__raypc.state(),
        note: document.getElementById('featuresStallNote').textContent, select: document.getElementById('featuresStallBy').value,
        warning: document.getElementById('featuresDepthWarning').hidden ? null : document.getElementById('featuresDepthWarning').textContent }));
    };
    const answers = () => page.evaluate(() => window.__raypc.featureAnswers.length);
    await page.click('#featuresDetails summary');

    // Cold material alone (temperature anomaly entirely below 0): the slabs' tip times the stalls.
    let n = await answers();
    await setBrushes([{ name: 'temperature anomaly', min: -10000, max: -25 }]);
    const cold = await answerAfter(n, 'a cold selection');
    console.log(`  cold: stallBy ${cold.state.features.stallBy}; '${cold.note}'`);
    // The server's answer says what it timed the stalls by: the request carried the implied measure.
    check(cold.f.stallBy === 'deepest', `a cold selection was answered with stalls by ${cold.f.stallBy}`);
    check(cold.state.features.stallBy === 'deepest' && cold.select === 'deepest' && /deepest/.test(cold.note) && /cold/.test(cold.note),
      `a cold selection is timed by ${cold.state.features.stallBy} (menu ${cold.select}); note '${cold.note}'`);
    check(cold.warning === null, `a selection without a depth brush warns: '${cold.warning}'`);
    // Hot material alone: the plumes' head.
    n = await answers();
    await setBrushes([{ name: 'temperature anomaly', min: 25, max: 10000 }]);
    const hot = await answerAfter(n, 'a hot selection');
    check(hot.f.stallBy === 'shallowest', `a hot selection was answered with stalls by ${hot.f.stallBy}`);
    check(hot.state.features.stallBy === 'shallowest' && /shallowest/.test(hot.note) && /hot/.test(hot.note),
      `a hot selection is timed by ${hot.state.features.stallBy}; note '${hot.note}'`);
    // Neither (a temperature range across 0): the mean depth.
    n = await answers();
    await setBrushes([{ name: 'temperature anomaly', min: -25, max: 25 }]);
    const mixed = await answerAfter(n, 'a selection across 0');
    check(mixed.state.features.stallBy === 'mean-depth' && /mean depth/.test(mixed.note),
      `a selection across 0 is timed by ${mixed.state.features.stallBy}; note '${mixed.note}'`);

    // The selection brushes depth: a warning that stalls near its ends are the brush's.
    n = await answers();
    const task1 = [{ name: 'depth', min: 560, max: 760 }, { name: 'temperature anomaly', min: -10000, max: -25 }];
    await setBrushes(task1);
    const brushed = await answerAfter(n, 'a selection brushing depth');
    const visible = await page.isVisible('#featuresDepthWarning');
    console.log(`  depth brushed: '${brushed.warning}'`);
    check(visible && brushed.warning !== null && /depth 560–760 km/.test(brushed.warning) && /artefact/.test(brushed.warning),
      `no visible warning that the selection brushes depth: '${brushed.warning}' (visible ${visible})`);

    // The user's choice stays when the brushes change in the page (a drag).
    n = await answers();
    await setBrushes([{ name: 'temperature anomaly', min: -10000, max: -25 }]);
    await answerAfter(n, 'the cold selection again');
    n = await answers();
    await page.selectOption('#featuresStallBy', 'shallowest');
    const chosen = await answerAfter(n, 'choosing the shallowest point');
    check(chosen.state.features.stallBy === 'shallowest' && /your choice/.test(chosen.note) && /implies the deepest/.test(chosen.note),
      `the choice of the shallowest point: ${chosen.state.features.stallBy}, '${chosen.note}'`);
    n = await answers();
    await brushAxis(page, 'lat', 0.05, 0.6);
    const dragged = await answerAfter(n, 'a brush dragged after the choice');
    check(dragged.state.brushes.length === 2 && dragged.state.features.stallBy === 'shallowest',
      `after a drag (brushes ${JSON.stringify(dragged.state.brushes.map((b) => b.name))}) the chosen measure gave way to ${dragged.state.features.stallBy}`);

    // A loaded document naming the default measure follows its selection again.
    n = await answers();
    await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, step: 0, features: { ...s.features, stallBy: 'mean-depth' },
      brushes: [{ name: 'depth', min: 0, max: 660 }, { name: 'lat', min: -90, max: -60 }, { name: 'lat', min: 60, max: 90 }] }); });
    const caps = await answerAfter(n, 'the polar caps');
    check(caps.state.features.stallBy === 'mean-depth' && !/your choice/.test(caps.note), `the polar caps: ${caps.state.features.stallBy}, '${caps.note}'`);
    // The caps do not move: timed at their own mean depth (from the answer) they stall there through
    // the series; the default depths are kept to give stalls of other lengths, 0 among them maybe.
    const own = [...new Set(caps.f.tracks.map((t) => Math.round(t.meanDepthKm)))];
    n = await answers();
    await page.evaluate((depthsKm) => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, features: { ...s.features, depthsKm } }); },
      [...own, ...caps.state.features.depthsKm].sort((a, b) => a - b));
    const timed = await answerAfter(n, 'the polar caps timed at their depths');

    // Every stall cell: "DEPTH km: T Myr", one line each, no zero-length stall; as many as the answer
    // has stalls longer than 0.
    const cells = await page.$$eval('#featuresTable td.stalls span.stall', (spans) => spans.map((e) => ({
      text: e.textContent, lines: e.getClientRects().length, height: e.getBoundingClientRect().height,
      lineHeight: parseFloat(getComputedStyle(e).lineHeight) || 1.3 * parseFloat(getComputedStyle(e).fontSize), cut: e.scrollWidth > e.clientWidth + 1,
      // Seen without scrolling sideways: inside the side panel (at 1366 px the table once ran past it).
      outside: (() => {  // the side panel's content box: its scroll bar hides what lies under it
        const side = document.getElementById('side');
        return e.getBoundingClientRect().right > side.getBoundingClientRect().left + side.clientLeft + side.clientWidth;
      })() })));
    const stalls = timed.f.tracks.flatMap((t) => t.stalls);
    const lasting = stalls.filter((s) => s.durationMyr > 0);
    console.log(`  ${stalls.length} stalls (${lasting.length} longer than 0): ${cells.map((c) => c.text).join(' | ')}`);
    check(lasting.length > 0, `the polar caps' tracks have no stall to show (${JSON.stringify(stalls)})`);
    check(cells.length === lasting.length, `${cells.length} stall lines in the table for ${lasting.length} stalls longer than 0 (${stalls.length} in all)`);
    for (const c of cells) {
      check(/^\d+(\.\d+)? km: \d+(\.\d)? Myr( [↓↑†])?$/.test(c.text) && !/: 0(\.0)? Myr/.test(c.text), `stall cell '${c.text}' without its units, or of 0 Myr`);
      check(c.lines === 1 && c.height < 1.6 * c.lineHeight && !c.cut, `stall cell '${c.text}' wraps or is cut (${c.lines} boxes, ${c.height.toFixed(1)} px high)`);
      check(!c.outside, `stall cell '${c.text}' lies past the side panel's right edge: the table is wider than the panel`);
    }

    // One id space: a chosen track is named by its id in the table, the legend and the highlight.
    const f = timed.f;
    const pick = f.tracks.find((t) => t.points.some((p) => p.step === 0 && p.feature !== t.track)) ?? f.tracks[0];
    await page.click(`#featuresTable tr[data-track="${pick.track}"]`);
    await page.waitForFunction(() => window.__raypc.state().features.highlight.length > 0, null, { timeout: 5000 });
    await page.waitForFunction((id) => [...document.querySelectorAll('#legends .legendTitle')].some((e) => e.textContent.includes(`track ${id}`)), pick.track, { timeout: 5000 })
      .catch(async () => { throw new TestFailure(`choosing track ${pick.track} (feature ${pick.points[0].feature} of step 0): the legend says ${JSON.stringify(await page.$$eval('#legends .legendTitle', (e) => e.map((x) => x.textContent)))}`); });
    const legend = await page.$$eval('#legends .legendTitle', (e) => e.map((x) => x.textContent).join(' | '));
    console.log(`  track ${pick.track} (feature ${pick.points[0].feature}): legend '${legend}'`);
    check(!/highlighted feature/.test(legend), `the legend names a feature id: '${legend}'`);
    const row = await page.textContent(`#featuresTable tr[data-track="${pick.track}"] td`);
    check(row.trim() === String(pick.track), `the table's row of track ${pick.track} reads '${row}'`);
  },

  // Issue 47, stale labels: a preset's name leaves the status line once the brushes are no longer
  // its own (Escape, a new brush); the note on the view of the colour variable goes while the view is
  // coloured by feature; reloading a state with exactly the preset's brushes keeps the preset in force.
  // Issue 47: the answer on the view, describing the frame shown. The readout (step, time, the
  // selection's share and volume at that step) is on the 3D view without scrolling; a figure of a
  // coarser level's grid says "≈"; a frame coarser than the view carries a badge; while playing,
  // every frame shown has its own step in the readout and the step label.
  async readout({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const ds = await info(url);
    const snap = () => page.evaluate(() => {
      const r = document.getElementById('viewReadout'), b = document.getElementById('coarseBadge');
      const box = r.getBoundingClientRect();
      return { readout: r.hidden ? null : r.textContent, badge: b.hidden ? null : b.textContent,
        shown: window.__raypc.shownLog.at(-1), stepLabel: document.getElementById('stepLabel').textContent,
        box: { top: box.top, bottom: box.bottom, left: box.left, right: box.right }, vw: innerWidth, vh: innerHeight,
        state: window.__raypc.state(), selection: window.__raypc.selection, status: document.getElementById('status').textContent };
    });
    let v = await snap();
    check(v.readout && v.readout.startsWith(`step ${v.state.step} · ${ds.steps[v.state.step].timeMyr.toFixed(1)} Myr`),
      `without brushes the readout says '${v.readout}': expected the step and its time`);
    check(v.badge === null, `a converged level-0 frame at the view's size has a badge: '${v.badge}'`);
    // The frame's cost is behind "Frame statistics": not in the status line by default.
    check(!/ms\/pass|samples\/s|bricks skipped/.test(v.status), `the status line shows developer statistics by default: '${v.status}'`);
    await page.check('#devStats');
    check(/ms\/pass/.test(await page.textContent('#status')), 'Frame statistics on: the status line has no ms/pass');
    await page.uncheck('#devStats');

    // A brush: the exact figure (POST /api/selection) on the view, within the window.
    await page.evaluate(() => {
      const s = window.__raypc.state();
      window.__raypc.setState({ ...s, brushes: [{ name: 'temperature anomaly', min: 25, max: 10000 }] });
    });
    await waitConverged(page);
    await page.waitForFunction(() => /% of the mantle selected/.test(document.getElementById('viewReadout').textContent) &&
      !document.getElementById('viewReadout').textContent.startsWith('≈'), null, { timeout: 15000 })
      .catch(async () => { throw new TestFailure(`no exact figure on the view: '${await page.textContent('#viewReadout')}'`); });
    v = await snap();
    const pct = Number(/([\d.]+) % of the mantle selected/.exec(v.readout)[1]);
    check(v.selection && Math.abs(pct - 100 * v.selection.fractionOfMantle) < 0.006,
      `the readout says ${pct} %, the exact selection is ${100 * v.selection?.fractionOfMantle} %`);
    check(/km³/.test(v.readout) && v.readout.includes(`step ${v.state.step}`), `the readout '${v.readout}' lacks the volume or the step`);
    check(v.box.top >= 0 && v.box.bottom <= v.vh && v.box.right <= v.vw && v.box.left >= 0,
      `the readout lies at ${JSON.stringify(v.box)} in a ${v.vw}x${v.vh} window`);

    // A coarser level asked for: the frame says so.
    await page.evaluate(() => window.__raypc.setState({ ...window.__raypc.state(), level: 2 }));
    await waitConverged(page);
    v = await snap();
    check(v.shown.level === 2 && v.badge && /level 2/.test(v.badge), `a level-2 frame: badge '${v.badge}' (frame level ${v.shown.level})`);
    await page.evaluate(() => window.__raypc.setState({ ...window.__raypc.state(), level: 'auto' }));
    await waitConverged(page);

    // Playing: sampled every 60 ms, the readout and the step label describe the frame on screen.
    await page.selectOption('#fps', '5');
    await page.click('#play');
    const seen = new Set();
    let approximate = 0, coarseBadges = 0, coarseFrames = 0;
    for (let i = 0; i < 60; i++) {
      await page.waitForTimeout(60);
      v = await snap();
      if (!v.shown) continue;
      seen.add(v.shown.step);
      check(v.readout.includes(`step ${v.shown.step} ·`), `playing: the frame shown is of step ${v.shown.step}, the readout says '${v.readout}'`);
      check(v.stepLabel.startsWith(`step ${v.shown.step} of`), `playing: the frame shown is of step ${v.shown.step}, the step label says '${v.stepLabel}'`);
      const coarse = v.shown.level > 0 || v.shown.width < v.state.image.width;
      if (coarse) coarseFrames++;
      if (coarse && v.badge) coarseBadges++;
      check(coarse || v.badge === null, `playing: a full frame (level ${v.shown.level}, ${v.shown.width} px) has the badge '${v.badge}'`);
      if (v.readout.startsWith('≈')) approximate++;
    }
    await page.click('#play');
    console.log(`  playing: steps seen ${[...seen].join(', ')}; coarse frames ${coarseFrames} (badged ${coarseBadges}); approximate figures ${approximate}`);
    check(seen.size >= 2, `playback showed only steps ${[...seen]}`);
    check(coarseBadges === coarseFrames, `${coarseFrames - coarseBadges} coarse frames shown without the badge`);
    await waitConverged(page);
    await page.waitForFunction(() => document.getElementById('coarseBadge').hidden && !document.getElementById('viewReadout').textContent.startsWith('≈'), null, { timeout: 15000 })
      .catch(async () => { throw new TestFailure(`paused: badge '${await page.textContent('#coarseBadge')}', readout '${await page.textContent('#viewReadout')}'`); });
  },

  // Issue 47: the shells' depth labels are written by the page over the frame (crisp at any frame
  // size), where the server's frame header says each goes; not while the frame is re-projected.
  async shell_labels({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const labels = () => page.evaluate(() => {
      const box = document.getElementById('shellLabels');
      const canvas = document.getElementById('view3d').getBoundingClientRect();
      return { hidden: box.hidden, header: window.__raypc.headers.at(-1).shellLabels ?? null,
        canvas: { left: canvas.left, top: canvas.top, right: canvas.right, bottom: canvas.bottom },
        spans: [...box.querySelectorAll('.shellLabel')].filter((e) => !e.hidden).map((e) => {
          const b = e.getBoundingClientRect();
          return { text: e.textContent, x: (b.left + b.right) / 2, y: (b.top + b.bottom) / 2, px: parseFloat(getComputedStyle(e).fontSize), color: getComputedStyle(e).color };
        }) };
    });
    let l = await labels();
    check(l.header && l.header.length === 2, `the frame header's shell labels: ${JSON.stringify(l.header)}; expected 410 and 660 km`);
    check(!l.hidden && l.spans.length === 2 && l.spans.map((x) => x.text).join(',') === l.header.map((x) => x.label).join(','),
      `the page writes ${JSON.stringify(l.spans.map((x) => x.text))} (hidden: ${l.hidden}) for the header's ${JSON.stringify(l.header.map((x) => x.label))}`);
    for (const [i, sp] of l.spans.entries()) {
      check(sp.px >= 12, `label ${sp.text} is ${sp.px} px`);
      check(sp.x > l.canvas.left && sp.x < l.canvas.right && sp.y > l.canvas.top && sp.y < l.canvas.bottom, `label ${sp.text} at ${sp.x}, ${sp.y} lies outside the view ${JSON.stringify(l.canvas)}`);
      const [r, g, b] = l.header[i].color.map((c) => Math.round(255 * c));
      check(sp.color === `rgb(${r}, ${g}, ${b})`, `label ${sp.text} is ${sp.color}, the shell is rgb(${r}, ${g}, ${b})`);
    }
    // Each label where the header puts it on the frame's picture, letterboxed into the view as drawn.
    const placed = await page.evaluate(() => {
      const h = window.__raypc.headers.at(-1), c = document.getElementById('view3d').getBoundingClientRect();
      let w = c.width, ht = w * h.height / h.width;
      if (ht > c.height) { ht = c.height; w = ht * h.width / h.height; }
      return { x: c.left + (c.width - w) / 2, y: c.top + (c.height - ht) / 2, w, h: ht };
    });
    l.spans.forEach((sp, i) => {
      const ex = placed.x + l.header[i].x * placed.w, ey = placed.y + l.header[i].y * placed.h;
      check(Math.abs(sp.x - ex) < 3 && Math.abs(sp.y - ey) < 3, `label ${sp.text} at ${sp.x.toFixed(1)}, ${sp.y.toFixed(1)}; the header puts it at ${ex.toFixed(1)}, ${ey.toFixed(1)}`);
    });
    console.log(`  labels ${l.spans.map((x) => `${x.text} at ${x.x.toFixed(0)},${x.y.toFixed(0)} (${x.px} px)`).join('; ')}`);
    // The surface's outline: the silhouette of the 6371 km sphere, here (the camera aimed at the
    // centre) a circle about the picture's centre of radius tan(asin(R / D)) / tan(fovY / 2) of half
    // its height; every drawn pixel lies inside it.
    const outline = await page.evaluate(() => {
      const poly = document.querySelector('#shellLabels polygon');
      const pts = (poly?.getAttribute('points') ?? '').trim().split(/\s+/).filter(Boolean).map((p) => p.split(',').map(Number));
      const c = document.getElementById('view3d').getBoundingClientRect();
      const h = window.__raypc.headers.at(-1), cam = window.__raypc.state().camera;
      let w = c.width, ht = w * h.height / h.width;
      if (ht > c.height) { ht = c.height; w = ht * h.width / h.height; }
      const cx = c.width / 2, cy = c.height / 2; // the polygon's points are the view's own (CSS px from its top left)
      const radius = Math.tan(Math.asin(6371 / cam.distanceKm)) / Math.tan(cam.fovYDeg * Math.PI / 360) * ht / 2;
      const dist = pts.map(([x, y]) => Math.hypot(x - cx, y - cy));
      const { data: d, width, height } = window.__viewImageData();
      let outside = 0;
      for (let y = 0; y < height; y++) for (let x = 0; x < width; x++) {
        const o = (y * width + x) * 4;
        if (Math.max(d[o], d[o + 1], d[o + 2]) > 40 && Math.hypot((x + 0.5) * c.width / width - cx, (y + 0.5) * c.height / height - cy) > radius + 2) outside++;
      }
      return { n: pts.length, radius, min: Math.min(...dist), max: Math.max(...dist), target: cam.targetKm, outside };
    });
    console.log(`  surface outline: ${outline.n} points at ${outline.min.toFixed(1)}-${outline.max.toFixed(1)} px from the centre; expected ${outline.radius.toFixed(1)}; drawn pixels outside it ${outline.outside}`);
    check(outline.target.every((t) => t === 0), `the default camera aims at ${outline.target}, not the centre`);
    check(outline.n >= 32 && Math.abs(outline.min - outline.radius) < 1.5 && Math.abs(outline.max - outline.radius) < 1.5,
      `the surface outline lies ${outline.min.toFixed(1)}-${outline.max.toFixed(1)} px from the centre, the sphere's silhouette ${outline.radius.toFixed(1)} px`);
    check(outline.outside === 0, `${outline.outside} drawn pixels lie outside the surface outline`);
    // Orbiting: while the frame is re-projected, the labels (of the frame's camera) are hidden.
    const c = await page.evaluate(() => document.getElementById('view3d').getBoundingClientRect());
    await page.mouse.move(c.left + c.width / 2, c.top + c.height / 2);
    await page.mouse.down();
    let hiddenWhileMoving = false;
    for (let i = 1; i <= 10; i++) {
      await page.mouse.move(c.left + c.width / 2 + 12 * i, c.top + c.height / 2 + 3 * i);
      const k = await page.evaluate(() => window.__raypc.drawnLog?.at?.(-1) ?? null);
      if (await page.evaluate(() => document.getElementById('shellLabels').hidden)) hiddenWhileMoving = true;
      void k;
    }
    await page.mouse.up();
    check(hiddenWhileMoving, 'the labels stayed while the view was re-projected to a moving camera');
    await waitConverged(page);
    await page.waitForFunction(() => !document.getElementById('shellLabels').hidden, null, { timeout: 10000 })
      .catch(() => { throw new TestFailure('the labels did not come back on the converged frame'); });
  },

  async preset_labels({ context, url, tmp }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const presets = await (await fetch(url + 'api/presets')).json();
    const p = presets.find((x) => x.name === 'task1-slabs-660km');
    check(p, `no preset task1-slabs-660km in ${presets.map((x) => x.name)}`);
    const status = () => page.textContent('#status');
    const apply = async () => {
      await page.click(`#presets button[data-preset="${p.name}"]`);
      await waitConverged(page);
      check((await status()).includes(`preset ${p.title}`), `the status line does not name the preset: '${await status()}'`);
    };
    await apply();

    // Coloured by feature, the note naming the colour variable goes; back to the variable, it returns.
    check(await page.isVisible('#viewNote'), 'no note on the view after the preset');
    await page.click('#featuresDetails summary');
    await page.check('#featuresColorById');
    await waitConverged(page);
    const noteWhileFeatures = await page.isVisible('#viewNote') ? await page.textContent('#viewNote') : null;
    check(noteWhileFeatures === null, `coloured by feature, the view still says '${noteWhileFeatures}'`);
    await page.uncheck('#featuresColorById');
    await waitConverged(page);
    check(await page.isVisible('#viewNote'), 'coloured by the variable again, the note on the view did not return');

    // Reloading a saved state with exactly the preset's brushes, while the preset is in force and
    // after its brushes were cleared: the preset is in force, not "brushes changed since".
    const file = join(tmp, 'task1.json');
    writeFileSync(file, JSON.stringify(await rState(page)));
    const reload = async (when) => {
      await page.setInputFiles('#load', file);
      await page.waitForFunction(() => document.getElementById('status').textContent.includes('loaded'), null, { timeout: 10000 });
      await waitConverged(page);
      const note = await page.textContent('#presetNote');
      const active = await page.$$eval('#presets button.active', (b) => b.map((x) => x.dataset.preset));
      console.log(`  reloaded ${when}: '${note}', active ${JSON.stringify(active)}`);
      check(!/changed since/.test(note) && note.startsWith(p.title) && active.length === 1 && active[0] === p.name,
        `reloading the preset's own brushes ${when}: '${note}', active ${JSON.stringify(active)}`);
    };
    await reload('with the preset in force');
    await page.mouse.click(5, 5);
    await page.keyboard.press('Escape');
    await page.waitForFunction(() => /changed since/.test(document.getElementById('presetNote').textContent), null, { timeout: 5000 })
      .catch(async () => { throw new TestFailure(`after Escape the preset note says '${await page.textContent('#presetNote')}'`); });
    await reload('after Escape');

    // Escape clears the brushes: the status line no longer names the preset.
    await apply();
    await page.mouse.click(5, 5);
    await page.keyboard.press('Escape');
    await page.waitForFunction(() => window.__raypc.state().brushes.length === 0, null, { timeout: 5000 });
    await waitConverged(page);
    check(!(await status()).includes(`preset ${p.title}`), `after Escape the status line still says '${await status()}'`);
    check(/changed since/.test(await page.textContent('#presetNote')), `after Escape the preset note says '${await page.textContent('#presetNote')}'`);

    // A new brush after the preset: the same.
    await apply();
    await brushAxis(page, 'temperature anomaly', 0.1, 0.3);
    await waitConverged(page);
    const brushes = (await rState(page)).brushes;
    check(brushes.length !== p.state.brushes.length || JSON.stringify(brushes) !== JSON.stringify(p.state.brushes), `the drag left the preset's brushes ${JSON.stringify(brushes)}`);
    check(!(await status()).includes(`preset ${p.title}`), `after a new brush the status line still says '${await status()}'`);
  },
  // Two datasets side by side (`raypc serve A B`, docs/compare.md): two synthetic runs of different
  // seeds, each in its own labelled half; one camera and one brush reach both (their frames' cameras
  // are the state's, the selection's figures of each are non-zero and differ); the parallel
  // coordinates draw both samples; a screenshot holds both; closing the second returns to one view
  // at the full width.
  async compare({ context, url, tmp }) {
    const page = await openUi(context, url);
    const pairInfo = (await info(url)).pair;
    check(pairInfo && pairInfo.datasets.length === 2, `GET /api/info has no pair: ${JSON.stringify(pairInfo)}`);
    const names = pairInfo.datasets.map((d) => d.name);
    check(names[0].endsWith('seed1') && names[1].endsWith('seed2'), `the pair's names are ${names.join(', ')}`);
    // Both views converged on the newest state (the second's frames are in pair.headers).
    const bothConverged = async () => {
      await waitConverged(page);
      await page.waitForFunction(() => {
        const p = window.__raypc.pair;
        const h = p?.headers[p.headers.length - 1];
        return h && h.converged && h.id === p.link.lastSentId;
      }, null, { timeout: 30000, polling: 50 }).catch(async () => {
        throw new TestFailure(`the second view has no converged frame of its newest state: ${JSON.stringify(await page.evaluate(() => window.__raypc.pair?.headers.slice(-1)))}`);
      });
    };
    await bothConverged();
    const boxes = await page.evaluate(() => ['view3d', 'view3dB'].map((id) => {
      const r = document.getElementById(id)?.getBoundingClientRect();
      return r ? { x: r.x, width: r.width } : null;
    }));
    const panel = await page.locator('#viewPanel').boundingBox();
    check(boxes[0] && boxes[1], `two views expected, found ${JSON.stringify(boxes)}`);
    check(Math.abs(boxes[0].width - panel.width / 2) <= 2 && Math.abs(boxes[1].width - panel.width / 2) <= 2 && boxes[1].x > boxes[0].x,
      `each view half of the ${panel.width} px panel side by side, found ${JSON.stringify(boxes)}`);
    const labels = async () => page.evaluate(() => ['pairLabelA', 'pairLabelB'].map((id) => document.getElementById(id)?.textContent ?? ''));
    let [la, lb] = await labels();
    check(la.includes(names[0]) && /step 0 \(0\.0 Myr\)/.test(la), `label A: '${la}'`);
    check(lb.includes(names[1]) && /step 0 \(0\.0 Myr\)/.test(lb), `label B: '${lb}'`);
    const state0 = await rState(page);
    check(state0.pair && state0.pair.dataset === names[1], `the state's pair: ${JSON.stringify(state0.pair)}`);

    // One camera: a drag on the first view turns both; both frames are of the state's camera.
    await drag(page, 160, 40);
    await bothConverged();
    const camera = (await rState(page)).camera;
    check(Math.abs(camera.azimuthDeg - state0.camera.azimuthDeg) > 5, `the drag did not turn the camera: ${JSON.stringify(camera)}`);
    const cams = await page.evaluate(() => {
      const a = window.__raypc.headers[window.__raypc.headers.length - 1], p = window.__raypc.pair;
      return [a.camera, p.headers[p.headers.length - 1].camera];
    });
    for (const [i, c] of cams.entries())
      check(Math.abs(c.azimuthDeg - camera.azimuthDeg) < 1e-6 && Math.abs(c.elevationDeg - camera.elevationDeg) < 1e-6,
        `view ${'AB'[i]}'s frame camera ${JSON.stringify(c)} is not the state's ${JSON.stringify(camera)}`);

    // The parallel coordinates draw both samples (the second's once it has loaded).
    await page.waitForFunction(() => window.__raypc.parcoords.timing.lines.foreground >= 2 * window.__raypc.parcoords.rowCount && window.__raypc.parcoords.timing.drawnAt.foreground > 0,
      null, { timeout: 20000 }).catch(async () => {
      throw new TestFailure(`the parallel coordinates do not draw both samples: ${JSON.stringify(await page.evaluate(() => [window.__raypc.parcoords.rowCount, window.__raypc.parcoords.timing.lines]))}`);
    });

    // One brush, applied to both by name: the selection's figures of each are non-zero and differ.
    await brushAxis(page, 'temperature anomaly', 0.05, 0.35);
    await bothConverged();
    const brushes = (await rState(page)).brushes;
    check(brushes.length === 1 && brushes[0].name === 'temperature anomaly', `brushes: ${JSON.stringify(brushes)}`);
    await page.waitForFunction(() => window.__raypc.selection && window.__raypc.pair.headers[window.__raypc.pair.headers.length - 1].selection,
      null, { timeout: 20000 });
    const figures = await page.evaluate(() => [window.__raypc.selection.fractionOfMantle,
      window.__raypc.pair.headers[window.__raypc.pair.headers.length - 1].selection.fractionOfMantle]);
    check(figures[0] > 0 && figures[1] > 0 && Math.abs(figures[0] - figures[1]) > 1e-6,
      `the selection of A and B: ${figures.join(', ')} (expected both non-zero and different: two seeds)`);
    [la, lb] = await labels();
    check(/selected \d+\.\d\d %/.test(la) && /selected \d+\.\d\d %/.test(lb), `the labels give the selections: '${la}' / '${lb}'`);
    // Each view's surface outline is a line, not a filled shape over the view.
    const fills = await page.evaluate(() => [...document.querySelectorAll('#shellLabels polygon, #shellLabelsB polygon')].map((p) => getComputedStyle(p).fill));
    check(fills.length === 2 && fills.every((f) => f === 'none'), `the views' surface outlines are filled: ${JSON.stringify(fills)}`);
    // "Compare A and B": the two runs' temperature anomaly correlated shell by shell (POST
    // /api/correlate), one point per shell with data, every r within [-1, 1]; runs of different seeds
    // are not the same field (r < 1 somewhere).
    await page.waitForFunction(() => Number(document.getElementById('pairCorrelation')?.dataset.points) > 0, null, { timeout: 20000 })
      .catch(async () => { throw new TestFailure(`no correlation per depth: '${await page.textContent('#pairCorrelationNote')}'`); });
    const corr = await page.evaluate(async () => {
      const r = await fetch('api/correlate', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(window.__raypc.state()) });
      return { status: r.status, body: await r.json(), points: Number(document.getElementById('pairCorrelation').dataset.points), note: document.getElementById('pairCorrelationNote').textContent };
    });
    const rs = corr.body.shells.map((x) => x.correlation).filter((x) => x !== null);
    console.log(`  correlation per depth: ${corr.points} points; r ${Math.min(...rs).toFixed(2)}..${Math.max(...rs).toFixed(2)}; '${corr.note}'`);
    check(corr.status === 200 && corr.points === rs.length && rs.length >= corr.body.shells.length - 2 && rs.every((x) => x >= -1 - 1e-9 && x <= 1 + 1e-9) && Math.min(...rs) < 0.999,
      `the pair's correlation: ${corr.points} points drawn of ${rs.length} (${corr.body.shells.length} shells), r ${Math.min(...rs)}..${Math.max(...rs)}`);
    check(corr.note.includes(`step ${corr.body.steps[0]}`) && /temperature anomaly/.test(corr.note), `the correlation's note: '${corr.note}'`);
    if (process.env.RAYPC_TEST_DEBUG) await page.screenshot({ path: join(process.env.RAYPC_TEST_DEBUG, 'compare.png') });
    // A screenshot of the pair holds both views: twice the width of one.
    const image = (await rState(page)).image;
    const shot = await screenshot(page, join(tmp, 'pair.png'));
    check(shot.width === 2 * image.width && shot.height === image.height,
      `the pair's screenshot is ${shot.width}x${shot.height}, expected ${2 * image.width}x${image.height} (two views of ${image.width}x${image.height})`);

    // Swap exchanges the sides; close returns to one view at the panel's full width.
    await page.click('#pairSwap');
    const swapped = await page.evaluate(() => ['view3d', 'view3dB'].map((id) => document.getElementById(id).getBoundingClientRect().x));
    check(swapped[0] > swapped[1], `after Swap the first view is not on the right: ${JSON.stringify(swapped)}`);
    const halfWidth = (await rState(page)).image.width;
    await page.click('#pairClose');
    await waitConverged(page);
    const after = await page.evaluate(() => ({ second: !!document.getElementById('view3dB'), pair: window.__raypc.pair, labels: document.querySelectorAll('.pairLabel').length,
      box: document.getElementById('view3d').getBoundingClientRect().width }));
    check(!after.second && after.pair === null && after.labels === 0, `after Close: ${JSON.stringify(after)}`);
    check(Math.abs(after.box - panel.width) <= 2, `after Close the view is ${after.box} px wide, the panel ${panel.width}`);
    const state1 = await rState(page);
    check(state1.pair === null && state1.image.width > 1.8 * halfWidth, `after Close the state: pair ${JSON.stringify(state1.pair)}, image ${JSON.stringify(state1.image)} (was ${halfWidth} wide)`);
    check(!page.raypcErrors.length, `page errors: ${page.raypcErrors.join(' | ')}`);
  },
  // Issue 47, the parallel coordinates (item 1), at 1366×768 and 1920×1080: full axis titles with
  // units (the Variable menu's names, never cut), text ≥ 12 px and WCAG AA contrast (text ≥ 4.5:1,
  // lines ≥ 3:1, from the computed styles over the panel's background), ARIA labels on axes and
  // tabs, brush-end labels clear of the titles, a range beyond its axis drawn at that end and said;
  // and a whole brush from the keyboard: Tab to an axis, type a range, the selected volume changes.
  async parcoords_access({ context, url }) {
    const page = await openUi(context, url);
    const info = await (await fetch(url + 'api/info')).json();
    const waitAxes = (w) => page.waitForFunction((w) => {
      const svg = document.querySelector('#parcoords svg');
      return svg && Math.abs(svg.getBoundingClientRect().width - w) < 40 && document.querySelectorAll('#parcoords g.dimension[tabindex]').length > 3;
    }, w, { timeout: 10000 }).catch(() => { throw new TestFailure(`the parallel coordinates were not redrawn at width ${w}`); });
    for (const [width, height] of [[1366, 768], [1920, 1080]]) {
      await page.setViewportSize({ width, height });
      await waitAxes(width);
      await page.waitForTimeout(300);
      const at = `${width}×${height}`;
      const facts = await page.evaluate(() => {
        const parse = (c) => (c.match(/[\d.]+/g) ?? []).map(Number);
        const lum = ([r, g, b]) => {
          const f = (v) => { v /= 255; return v <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4; };
          return 0.2126 * f(r) + 0.7152 * f(g) + 0.0722 * f(b);
        };
        const panel = document.querySelector('#parcoords .parcoords') ?? document.querySelector('#parcoords');
        const bg = parse(getComputedStyle(panel).backgroundColor).slice(0, 3);
        // The colour as drawn: its alpha, fill-/stroke-opacity and every opacity up to the panel, over the background.
        const drawn = (el, prop) => {
          const cs = getComputedStyle(el);
          const c = parse(cs[prop]);
          let a = (c.length > 3 ? c[3] : 1) * Number(cs[prop === 'fill' ? 'fillOpacity' : 'strokeOpacity']);
          for (let e = el; e && e !== panel; e = e.parentElement) a *= Number(getComputedStyle(e).opacity);
          return c.slice(0, 3).map((v, i) => v * a + bg[i] * (1 - a));
        };
        const ratio = (fg) => { const l1 = lum(fg), l2 = lum(bg); return (Math.max(l1, l2) + 0.05) / (Math.min(l1, l2) + 0.05); };
        const svg = document.querySelector('#parcoords svg').getBoundingClientRect();
        const axes = [...document.querySelectorAll('#parcoords g.dimension')].map((g) => {
          const label = g.querySelector('text.label');
          const r = label.getBoundingClientRect();
          return { name: g.__data__, title: ([...label.querySelectorAll('tspan')].map((t) => t.textContent).join(' ') || label.textContent).replace(/- /g, '-'),
            aria: g.getAttribute('aria-label'), tabindex: g.getAttribute('tabindex'),
            box: { left: r.left, right: r.right, top: r.top, bottom: r.bottom } };
        });
        const texts = [...document.querySelectorAll('#parcoords svg text')].filter((t) => t.getBoundingClientRect().width > 0);
        const small = texts.map((t) => [t.textContent, parseFloat(getComputedStyle(t).fontSize)]).filter(([, px]) => px < 12);
        const lowText = texts.map((t) => [t.textContent, ratio(drawn(t, 'fill'))]).filter(([, r]) => r < 4.5);
        const lines = [...document.querySelectorAll('#parcoords .axis path.domain, #parcoords .axis .tick line')];
        const lowLines = lines.map((l) => ratio(drawn(l, 'stroke'))).filter((r) => r < 3);
        const tabs = [...document.querySelectorAll('#pcTabs [role=tab]')].map((b) => ({ id: b.id, label: b.getAttribute('aria-label') ?? b.textContent, selected: b.getAttribute('aria-selected') }));
        const unnamed = [...document.querySelectorAll('#pcPanel button, #pcPanel summary')].filter((b) => !b.hidden && !(b.getAttribute('aria-label') || /[A-Za-z]{2}/.test(b.textContent))).map((b) => b.outerHTML.slice(0, 80));
        return { bg, axes, small, lowText, lowLines, lineCount: lines.length, tabs, unnamed, svg: { left: svg.left, right: svg.right, top: svg.top } };
      });
      check(facts.lineCount > 5, `${at}: no axis lines found`);
      check(facts.small.length === 0, `${at}: text under 12 px in the parallel coordinates: ${JSON.stringify(facts.small.slice(0, 5))}`);
      check(facts.lowText.length === 0, `${at}: text under 4.5:1 against the panel ${facts.bg}: ${JSON.stringify(facts.lowText.slice(0, 5))}`);
      check(facts.lowLines.length === 0, `${at}: axis lines under 3:1 against the panel: ${JSON.stringify(facts.lowLines.slice(0, 5))}`);
      check(facts.tabs.length === 3 && facts.tabs.every((t) => t.label && t.selected !== null), `${at}: tabs without role, label or aria-selected: ${JSON.stringify(facts.tabs)}`);
      check(facts.unnamed.length === 0, `${at}: buttons without an accessible name: ${JSON.stringify(facts.unnamed)}`);
      for (const a of facts.axes) {
        const v = info.variables.find((x) => x.name === a.name) ?? info.coordinates.find((x) => x.name === a.name);
        check(v, `${at}: axis '${a.name}' is not a variable or coordinate of /api/info`);
        const full = await page.evaluate((n) => [...document.querySelectorAll('#variable option')].some((o) => o.textContent === n || o.value === n), a.name);
        if (info.variables.some((x) => x.name === a.name)) check(full, `${at}: axis '${a.name}' is not a name of the Variable menu`);
        const title = a.title.replace(/…$/, '');
        check(title.length > 0 && (a.title.endsWith('…') ? `${a.name} [`.startsWith(title.slice(0, a.name.length + 2)) || a.name.startsWith(title) : a.title.startsWith(`${a.name} [`) || a.title === a.name),
          `${at}: axis '${a.name}' is titled '${a.title}', not by its full name with units`);
        check(a.aria && a.aria.startsWith(a.name) && a.tabindex === '0', `${at}: axis '${a.name}' has aria-label '${a.aria}', tabindex ${a.tabindex}`);
        check(a.box.left >= facts.svg.left - 1 && a.box.right <= facts.svg.right + 1 && a.box.top >= facts.svg.top - 1, `${at}: the title of '${a.name}' is cut at the panel's edge: ${JSON.stringify(a.box)} in ${JSON.stringify(facts.svg)}`);
      }
      const sorted = [...facts.axes].sort((p, q) => p.box.left - q.box.left);
      for (let i = 1; i < sorted.length; i++)
        check(sorted[i].box.left >= sorted[i - 1].box.right - 1, `${at}: titles '${sorted[i - 1].title}' and '${sorted[i].title}' overlap`);
      check(facts.axes.some((a) => a.name === 'spin transition-induced density anomaly' && a.aria.startsWith('spin transition-induced density anomaly [')) || !info.variables.some((v) => v.name.startsWith('spin')),
        `${at}: the spin transition's axis is not titled by its full name: ${JSON.stringify(facts.axes.map((a) => a.title))}`);
    }

    // The whole brush from the keyboard, at 1366×768: from the tab bar, Tab to the first axis, → to
    // depth, type a range, Enter.
    await page.setViewportSize({ width: 1366, height: 768 });
    await waitAxes(1366);
    await page.waitForTimeout(300);
    const focused = () => page.evaluate(() => document.activeElement?.__data__ ?? document.activeElement?.id ?? document.activeElement?.tagName);
    await page.focus('#pcTabVolume');
    const isAxis = () => page.evaluate(() => document.activeElement?.matches?.('#parcoords g.dimension') ?? false);
    for (let i = 0; i < 10 && !(await isAxis()); i++) await page.keyboard.press('Tab');
    check(await isAxis(), `Tab from the tab bar never reached an axis (focus on ${await focused()})`);
    const order = await page.evaluate(() => window.__raypc.parcoords.order());
    for (let i = 0; i < order.length && (await focused()) !== 'depth'; i++) await page.keyboard.press('ArrowRight');
    check((await focused()) === 'depth', `→ did not reach the depth axis (focus on ${await focused()})`);
    const before = await page.textContent('#selection');
    await page.keyboard.type('560-760');
    await page.keyboard.press('Enter');
    await waitConverged(page);
    let brushes = (await rState(page)).brushes;
    check(brushes.length === 1 && brushes[0].name === 'depth' && brushes[0].min === 560 && brushes[0].max === 760, `typing 560-760 on depth gave brushes ${JSON.stringify(brushes)}`);
    await page.waitForFunction((b) => /% of the mantle/.test(document.querySelector('#selection').textContent) && document.querySelector('#selection').textContent !== b, before, { timeout: 10000 })
      .catch(async () => { throw new TestFailure(`the selection still reads '${await page.textContent('#selection')}' after a typed brush`); });
    const first = await page.textContent('#selectionValue');
    check((await focused()) === 'depth', `after Enter the focus is on ${await focused()}, not the depth axis`);
    // ↑ moves the brush towards the top of the screen: smaller depths, one snap step.
    await page.keyboard.press('ArrowUp');
    await waitConverged(page);
    brushes = (await rState(page)).brushes;
    check(brushes.length === 1 && brushes[0].max < 760 && brushes[0].max - brushes[0].min === 200, `↑ on depth 560–760 gave ${JSON.stringify(brushes)}`);
    await page.waitForFunction((f) => document.querySelector('#selectionValue')?.textContent !== f, first, { timeout: 10000 })
      .catch(() => { throw new TestFailure(`the selection stayed '${first}' after ↑ moved the brush`); });
    // The brush-end labels stay clear of the titles: a range up to the axis' top end (depth 0 km).
    await page.keyboard.type('0-300');
    await page.keyboard.press('Enter');
    await waitConverged(page);
    const clash = await page.evaluate(() => {
      const out = [];
      for (const g of document.querySelectorAll('#parcoords g.dimension')) {
        const t = g.querySelector('text.label').getBoundingClientRect();
        for (const l of g.querySelectorAll('text.brushLabel')) {
          const r = l.getBoundingClientRect();
          if (r.left < t.right && r.right > t.left && r.top < t.bottom && r.bottom > t.top) out.push(`${g.__data__}: '${l.textContent}' over '${g.querySelector('text.label').textContent}'`);
        }
      }
      return { out, labels: document.querySelectorAll('#parcoords text.brushLabel').length };
    });
    check(clash.labels >= 2 && clash.out.length === 0, `brush-end labels over axis titles: ${JSON.stringify(clash)}`);
    // Escape on the axis clears its brush (and only that).
    await page.keyboard.press('Escape');
    await waitConverged(page);
    brushes = (await rState(page)).brushes;
    check(brushes.length === 0, `Escape on the depth axis left ${JSON.stringify(brushes)}`);
    await page.waitForFunction(() => /no brushes/.test(document.querySelector('#selection').textContent), null, { timeout: 5000 })
      .catch(async () => { throw new TestFailure(`after Escape the selection reads '${await page.textContent('#selection')}'`); });
    check((await focused()) === 'depth', `after Escape the focus is on ${await focused()}`);

    // A range wholly beyond its axis (as preset 1's radial velocity ≤ 0 on a model whose values are
    // all positive): kept, drawn as a mark at that end, and said in its label and ARIA label.
    const t = info.variables.find((v) => v.name === 'temperature anomaly');
    const beyond = { name: 'temperature anomaly', min: t.min - 500, max: t.min - 100 };
    await page.evaluate((b) => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, brushes: [b] }); }, beyond);
    await waitConverged(page);
    await page.waitForFunction(() => document.querySelector('#parcoords rect.brushOutside'), null, { timeout: 5000 })
      .catch(() => { throw new TestFailure('a brush below the temperature anomaly axis draws no mark at its end'); });
    const said = await page.evaluate(() => {
      const g = [...document.querySelectorAll('#parcoords g.dimension')].find((x) => x.__data__ === 'temperature anomaly');
      const mark = g.querySelector('rect.brushOutside').getBoundingClientRect();
      const domain = g.querySelector('.axis path.domain').getBoundingClientRect();
      return { labels: [...g.querySelectorAll('text.brushLabel')].map((l) => l.textContent), aria: g.getAttribute('aria-label'),
        markY: mark.top + mark.height / 2, axisTop: domain.top, axisBottom: domain.bottom };
    });
    check(said.labels.some((l) => /below the axis/.test(l)), `the label of a brush below the axis says ${JSON.stringify(said.labels)}`);
    check(/below the axis/.test(said.aria), `the axis' ARIA label does not say the brush is below it: '${said.aria}'`);
    check(Math.abs(said.markY - said.axisBottom) < 12, `the mark of a brush below the axis is at y ${said.markY}, not at the axis' low end ${said.axisBottom}`);
    brushes = (await rState(page)).brushes;
    check(brushes.length === 1 && brushes[0].max === beyond.max, `the brush beyond the axis was dropped or changed: ${JSON.stringify(brushes)}`);
    check(page.raypcErrors.length === 0, `page errors: ${page.raypcErrors.join(' | ')}`);
  },
  // Issue 47, an empty selection says so (item 2): preset 1 (radial velocity ≤ 0) on the fixture,
  // whose radial velocity is positive everywhere, selects nothing; a note under the figure names the
  // radial velocity brush as the one that selects nothing by itself, from the server's answer.
  async empty_selection({ context, url }) {
    const page = await openUi(context, url);
    await page.click('#presets button[data-preset="task1-slabs-660km"]');
    await waitConverged(page);
    await page.waitForFunction(() => { const e = document.querySelector('#emptySelection'); return e && !e.hidden && e.textContent; }, null, { timeout: 10000 })
      .catch(async () => { throw new TestFailure(`no empty-selection note; the selection reads '${await page.textContent('#selection')}'`); });
    const note = await page.textContent('#emptySelection');
    const state = await rState(page);
    const answer = await postJson(url + 'api/selection', state);
    check(answer.status === 200 && answer.body.fractionOfMantle === 0, `the preset's selection is ${JSON.stringify(answer.body)}, not empty`);
    const empty = answer.body.empty ?? [];
    check(empty.length === new Set(state.brushes.map((b) => b.name)).size, `the server's 'empty' ${JSON.stringify(empty)} does not list every brushed axis`);
    const zero = empty.filter((e) => e.alone === 0).map((e) => e.name);
    check(zero.includes('radial velocity'), `the server does not say radial velocity ≤ 0 selects nothing alone: ${JSON.stringify(empty)}`);
    for (const e of empty.filter((x) => x.alone > 0)) check(!note.includes(e.name), `the note '${note}' blames ${e.name}, which selects ${e.alone} alone`);
    check(note.includes('radial velocity') && /nothing by itself/.test(note), `the note '${note}' does not name the radial velocity brush`);
    check(/0\.00 %/.test(await page.textContent('#selection')), `the selection reads '${await page.textContent('#selection')}'`);
    const box = await page.locator('#emptySelection').boundingBox();
    check(box && box.height > 0, 'the empty-selection note is not drawn');
    // A selection with something in it: no note.
    await page.evaluate(() => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, brushes: [{ name: 'depth', min: 560, max: 760 }] }); });
    await waitConverged(page);
    await page.waitForFunction(() => document.querySelector('#emptySelection').hidden, null, { timeout: 10000 })
      .catch(async () => { throw new TestFailure(`the note stays for a selection of ${await page.textContent('#selection')}: '${await page.textContent('#emptySelection')}'`); });
    check(page.raypcErrors.length === 0, `page errors: ${page.raypcErrors.join(' | ')}`);
  },

  // Issue 47, colours that cannot be mistaken (item 4): one default colour range per variable — the
  // default view, the presets that colour by the same variable and /api/info show the same range,
  // symmetric (the temperature anomaly was ±451.8 K in one and ±300 K in the others); and the map
  // draws what the brushes leave out hatched and dark, never in a grey that a diverging map's light
  // neutral (a stalled slab, v_r ≈ 0) could be read as.
  async colours_unmistakable({ context, url }) {
    const page = await openUi(context, url);
    await waitConverged(page);
    const shownRange = () => page.evaluate(() => [Number(document.getElementById('rangeMin').value), Number(document.getElementById('rangeMax').value)]);
    const near = (a, b) => Math.abs(a[0] - b[0]) <= 1e-4 * Math.abs(b[1]) && Math.abs(a[1] - b[1]) <= 1e-4 * Math.abs(b[1]);
    const variable = (await rState(page)).color.variable;
    const v = (await info(url)).variables.find((x) => x.name === variable);
    const d = v.defaultColorRange.centred;
    const first = await shownRange();
    check(d[0] === -d[1] && d[1] <= Math.max(-v.min, v.max) * (1 + 1e-6), `/api/info's default range of ${variable} ${JSON.stringify(d)} is not symmetric within the data's ${v.min}..${v.max}`);
    check(near(first, d), `the default view shows ${variable} over ${JSON.stringify(first)}, /api/info's default range is ${JSON.stringify(d)}`);
    const presets = (await (await fetch(url + 'api/presets')).json())
      .filter((p) => !p.unavailable && p.state.color.variable === variable && p.state.color.colorMap === 'blue-white-red');
    check(presets.length >= 2, `only ${presets.length} presets colour by ${variable}`);
    for (const p of presets) {
      await page.click(`#presets button[data-preset="${p.name}"]`);
      await waitConverged(page);
      const r = await shownRange();
      check(near(r, first), `preset ${p.name} shows ${variable} over ${JSON.stringify(r)}, the default view over ${JSON.stringify(first)}`);
    }
    // The map of the warm half (temperature anomaly ≥ 0) at 660 km: the cold half is hatched dark grey.
    await page.click('#pcTabSlices');
    await page.evaluate((name) => { const s = window.__raypc.state(); window.__raypc.setState({ ...s, brushes: [{ name, min: 0, max: 1e6 }], map: { ...s.map, greyUnselected: true, depthKm: 660 } }); }, variable);
    await waitConverged(page);
    await page.waitForFunction(() => window.__raypc.slices.map.header && document.getElementById('mapImage').complete, null, { timeout: 20000 })
      .catch(() => { throw new TestFailure('no map picture'); });
    await page.waitForTimeout(1500);
    const grey = await page.evaluate(() => {
      const img = document.getElementById('mapImage');
      const c = document.createElement('canvas');
      c.width = img.naturalWidth; c.height = img.naturalHeight;
      const g = c.getContext('2d');
      g.drawImage(img, 0, 0);
      const { data } = g.getImageData(0, 0, c.width, c.height);
      // Blocks of 6×6 pixels all of one grey (r = g = b) but the background's: their darkest and lightest.
      const bg = [data[0], data[1], data[2]];
      const blocks = [];
      for (let y = 0; y + 6 <= c.height; y += 6)
        for (let x = 0; x + 6 <= c.width; x += 6) {
          let lo = 255, hi = 0, ok = true;
          for (let dy = 0; dy < 6 && ok; dy++)
            for (let dx = 0; dx < 6 && ok; dx++) {
              const i = ((y + dy) * c.width + x + dx) * 4;
              if (data[i] !== data[i + 1] || data[i + 1] !== data[i + 2] || (data[i] === bg[0] && data[i + 1] === bg[1] && data[i + 2] === bg[2])) ok = false;
              lo = Math.min(lo, data[i]); hi = Math.max(hi, data[i]);
            }
          if (ok) blocks.push([lo, hi]);
        }
      return blocks;
    });
    check(grey.length >= 20, `the map has ${grey.length} grey blocks: nothing drawn as not selected`);
    const hatched = grey.filter(([lo, hi]) => hi - lo >= 35 && lo <= 70).length;
    check(hatched >= 0.8 * grey.length, `${hatched} of ${grey.length} grey blocks of the map are hatched and dark; not selected must be drawn as no colour map draws`);
    check(page.raypcErrors.length === 0, `page errors: ${page.raypcErrors.join(' | ')}`);
  },

  // Issue 47, derived and stored variables told apart (item 3): /api/info says how each variable is
  // made (derived, source, computed), and the Variable menu's options and the axes' tooltips say it.
  async variable_origin({ context, url }) {
    const info = await (await fetch(url + 'api/info')).json();
    for (const v of info.variables) check(typeof v.source === 'string', `/api/info: variable '${v.name}' has no source`);
    const derived = info.variables.find((v) => v.name === 'radial velocity');
    check(derived && derived.derived && /vx/.test(derived.source), `/api/info: radial velocity is ${JSON.stringify(derived && { derived: derived.derived, source: derived.source })}`);
    const computed = info.variables.filter((v) => v.computed);
    check(computed.length > 0 && computed.every((v) => info.variables.some((b) => b.name === v.computed.from && !b.computed)),
      `/api/info: computed variables ${JSON.stringify(computed.map((v) => [v.name, v.computed]))}`);
    const stored = info.variables.filter((v) => !v.derived && !v.computed);
    check(stored.length > 0, '/api/info: no stored variable');
    const page = await openUi(context, url);
    const titles = await page.evaluate(() => Object.fromEntries([...document.querySelectorAll('#variable option')].map((o) => [o.value, o.title])));
    for (const v of info.variables) {
      const t = titles[v.name] ?? '';
      const want = v.computed ? new RegExp(`computed when read: ${v.computed.from.replace(/[.*+?^${}()|[\]\\]/g, '\\$&')}`) : v.derived ? /derived at preprocessing from/ : /stored: read from the input files/;
      check(want.test(t), `the Variable menu's '${v.name}' says '${t}', expected ${want}`);
    }
    const axisTips = await page.evaluate(() => Object.fromEntries([...document.querySelectorAll('#parcoords g.dimension')].map((g) => [g.__data__, g.querySelector('text.label').parentNode.querySelector(':scope > title')?.textContent ?? ''])));
    for (const v of info.variables.filter((x) => axisTips[x.name] !== undefined)) {
      check(axisTips[v.name].includes(titles[v.name].split(': ').slice(1).join(': ')), `the axis '${v.name}' tooltip '${axisTips[v.name]}' does not say how it is made`);
    }
    check(page.raypcErrors.length === 0, `page errors: ${page.raypcErrors.join(' | ')}`);
  },
  // Issue 47, maps and sections linked (item 4), at 1366×768 and 1920×1080: the section's line and
  // its ends A and B drawn over the map where the map's projection puts them (within a few pixels of
  // where the probe's inverse finds the ends), a graticule and coastlines drawn by default, and a
  // hint that says which end the next click sets.
  async map_section({ context, url }) {
    const page = await openUi(context, url);
    await page.click('#pcTabSlices');
    for (const [width, height] of [[1366, 768], [1920, 1080]]) {
      const at = `${width}×${height}`;
      await page.setViewportSize({ width, height });
      const before = await page.evaluate(() => window.__raypc.slices.map.shown);
      await page.waitForFunction((b) => window.__raypc.slices.map.shown > b || (b > 0 && window.__raypc.slices.map.header), before, { timeout: 20000 }).catch(() => {});
      await page.waitForFunction(() => window.__raypc.slices.map.header && document.getElementById('mapImage').complete, null, { timeout: 20000 })
        .catch(() => { throw new TestFailure(`${at}: no map picture`); });
      await page.waitForTimeout(700);
      // Two clicks on the map: A, then B; the hint names the end the next click sets.
      const hint = () => page.textContent('#mapReadout');
      await page.mouse.move(1, 1);
      await page.waitForTimeout(200);
      const first = await hint();
      check(/sets A/.test(first), `${at}: before the first click the hint says '${first}'`);
      const img = await page.locator('#mapImage').boundingBox();
      const onMap = async (fx, fy) => {
        // A point of the map's sphere: the picture's pixels inverted by the projection (slice_panel.ts).
        return page.evaluate(([fx, fy]) => {
          const h = window.__raypc.slices.map.header, el = document.getElementById('mapImage').getBoundingClientRect();
          const css = Math.min(el.width / h.width, el.height / h.height);
          const px = h.centre[0] + (fx - 0.5) * 2 * h.scale, py = h.centre[1] + (fy - 0.5) * h.scale;
          const ll = window.__raypc.slices.lonLatOnMap(px, py);
          return ll && { x: el.left + px * css, y: el.top + py * css, lon: ll[0], lat: ll[1] };
        }, [fx, fy]);
      };
      const a = await onMap(0.35, 0.45), b = await onMap(0.65, 0.6);
      check(a && b, `${at}: no point of the sphere at the chosen places (${JSON.stringify([a, b])})`);
      await page.mouse.click(a.x, a.y);
      await page.mouse.move(1, 1);
      await page.waitForTimeout(300);
      check(/sets B/.test(await hint()), `${at}: after the first click the hint says '${await hint()}'`);
      await page.mouse.click(b.x, b.y);
      await page.mouse.move(1, 1);
      await page.waitForTimeout(300);
      check(/sets A/.test(await hint()), `${at}: after the second click the hint says '${await hint()}'`);
      const section = (await rState(page)).section;
      check(Math.abs(section.from.lonDeg - a.lon) < 2.5 && Math.abs(section.to.lonDeg - b.lon) < 2.5, `${at}: the clicks set the section ${JSON.stringify(section)}, not A ${a.lon} and B ${b.lon}`);
      await page.waitForTimeout(300);
      const marks = await page.evaluate(() => {
        const box = (e) => { const r = e.getBoundingClientRect(); return { x: r.x + r.width / 2, y: r.y + r.height / 2, w: r.width, h: r.height }; };
        const ends = Object.fromEntries([...document.querySelectorAll('#mapMarks .sectionEnd')].map((g) => [g.dataset.end, { ...box(g.querySelector('circle')), label: g.querySelector('text').textContent }]));
        const line = document.querySelector('#mapMarks .sectionLine');
        return { ends, line: line ? box(line) : null, graticule: document.querySelector('#mapMarks .graticule')?.getAttribute('d')?.length ?? 0,
          coast: document.querySelector('#mapMarks .coastline')?.getAttribute('d')?.length ?? 0,
          labels: [...document.querySelectorAll('#mapMarks .graticuleLabel')].map((t) => t.textContent) };
      });
      check(marks.ends.A?.label === 'A' && marks.ends.B?.label === 'B', `${at}: the section's ends are not drawn labelled A and B: ${JSON.stringify(marks.ends)}`);
      check(Math.hypot(marks.ends.A.x - a.x, marks.ends.A.y - a.y) < 4 && Math.hypot(marks.ends.B.x - b.x, marks.ends.B.y - b.y) < 4,
        `${at}: A drawn at ${marks.ends.A.x},${marks.ends.A.y} and B at ${marks.ends.B.x},${marks.ends.B.y}, clicked at ${a.x},${a.y} and ${b.x},${b.y}`);
      check(marks.line && marks.line.w > Math.abs(b.x - a.x) * 0.8, `${at}: the section's line is not drawn between its ends: ${JSON.stringify(marks.line)}`);
      check(marks.graticule > 100 && marks.labels.some((l) => l === '30°N') && marks.coast > 1000, `${at}: no graticule, its labels or the coastlines on the map by default: ${JSON.stringify({ graticule: marks.graticule, coast: marks.coast, labels: marks.labels })}`);
    }
    check(page.raypcErrors.length === 0, `page errors: ${page.raypcErrors.join(' | ')}`);
  },
  // Issue 47, item 1: at 10 steps/s the parallel coordinates showed no selected line. Playing at
  // 10 steps/s with a brush in force, sampled every 120 ms: the brushed layer always shows lines
  // (its canvas differs from the veil), the step they are of (#pcStep, linesStep) is a step whose
  // frame was on screen, and they follow the playback (several steps); the Selection panel's figure
  // names the step of a frame shown and the statistics' profile is of the store's step.
  async play_lines({ context, url }) {
    const page = await openUi(context, url);
    const nSteps = (await info(url)).steps.length;
    await brushAxis(page, 'temperature anomaly', 0.15, 0.55);
    await waitConverged(page);
    await page.waitForFunction(() => window.__raypc.stats && window.__raypc.linesStep >= 0 && window.__raypc.parcoords.timing.drawnAt.brushed > 0, null, { timeout: 30000 })
      .catch(() => { throw new TestFailure('no statistics or no lines drawn after the brush'); });
    const linePixels = () => page.evaluate(() => {
      // The brushed layer: the veil is one colour everywhere; a line is any other.
      const c = document.querySelector('#parcoords canvas.brushed');
      const d = c.getContext('2d', { willReadFrequently: true }).getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 0; i < d.length; i += 16) if (Math.abs(d[i] - d[0]) + Math.abs(d[i + 1] - d[1]) + Math.abs(d[i + 2] - d[2]) + Math.abs(d[i + 3] - d[3]) > 8) n++;
      return n;
    });
    await page.waitForFunction(() => window.__raypc.parcoords.timing.lines.brushed > 0 && window.__raypc.parcoords.timing.drawnAt.brushed > 0, null, { timeout: 30000 })
      .catch(async () => { throw new TestFailure(`no brushed lines drawn after the brush: ${JSON.stringify(await page.evaluate(() => ({ brushes: window.__raypc.state().brushes, timing: window.__raypc.parcoords.timing })))}`); });
    const paused = await linePixels();
    check(paused > 200, `paused, the brushed layer shows ${paused} line pixels`);
    await page.selectOption('#fps', '10');
    const t0 = await page.evaluate(() => performance.now());
    await page.click('#play');
    const samples = [];
    const until = Date.now() + 9000;
    while (Date.now() < until) {
      await page.waitForTimeout(120);
      samples.push(await page.evaluate((since) => {
        const r = window.__raypc;
        // The brushed layer: the veil is one colour everywhere; a line is any other.
        const c = document.querySelector('#parcoords canvas.brushed');
        const d = c.getContext('2d', { willReadFrequently: true }).getImageData(0, 0, c.width, c.height).data;
        let pixels = 0;
        for (let i = 0; i < d.length; i += 16) if (Math.abs(d[i] - d[0]) + Math.abs(d[i + 1] - d[1]) + Math.abs(d[i + 2] - d[2]) + Math.abs(d[i + 3] - d[3]) > 8) pixels++;
        const shown = r.shownLog.filter((e) => e.t >= since).map((e) => e.step);
        return { pixels, linesStep: r.linesStep, label: document.getElementById('pcStep').textContent, shown: [...new Set(shown)],
          selection: document.getElementById('selectionValue')?.textContent ?? '', storeStep: r.state().step, profileStep: r.stats?.profile.step };
      }, t0));
    }
    await page.click('#play');
    const steps = new Set();
    let named = 0;
    for (const [i, x] of samples.entries()) {
      check(x.pixels > 200, `sample ${i} (${(120 * i / 1000).toFixed(1)} s into playback): the brushed layer shows no lines (${x.pixels} line pixels)`);
      // The initial step (0) was on screen before playback.
      check(x.linesStep === 0 || x.shown.includes(x.linesStep), `sample ${i}: the lines are of step ${x.linesStep}, not a step shown (${x.shown.join(',')})`);
      check(x.label.startsWith(`lines: step ${x.linesStep} `), `sample ${i}: the label over the lines says '${x.label}', the lines are of step ${x.linesStep}`);
      steps.add(x.linesStep);
      const m = /^step (\d+): /.exec(x.selection);
      if (m) {
        named++;
        check(x.shown.includes(Number(m[1])) || Number(m[1]) === 0, `sample ${i}: the Selection panel's figure is of step ${m[1]}, not a step shown`);
      }
      if (x.profileStep !== undefined) check(x.profileStep === x.storeStep, `sample ${i}: the statistics' profile is of step ${x.profileStep}, the store's step is ${x.storeStep}`);
    }
    const shownSteps = new Set(samples.at(-1).shown);
    console.log(`  ${samples.length} samples; lines of steps ${[...steps].join(',')}; frames of ${shownSteps.size} steps shown; the selection named its step in ${named}`);
    check(shownSteps.size >= Math.min(nSteps, 4), `playback showed the steps ${[...shownSteps].join(',')} only`);
    check(steps.size >= 2, `the lines stayed at step ${[...steps].join(',')} through playback`);
    check(named >= samples.length / 2, `the Selection panel named its step in ${named} of ${samples.length} samples`);
    // Paused: the lines are of the step shown again.
    await waitConverged(page);
    await page.waitForFunction(() => window.__raypc.linesStep === window.__raypc.state().step, null, { timeout: 20000 })
      .catch(async () => { throw new TestFailure(`after pausing the lines are of step ${await page.evaluate(() => window.__raypc.linesStep)}`); });
    check(page.raypcErrors.length === 0, `page errors: ${page.raypcErrors.join(' | ')}`);
  },

  // Issue 47, item 5: the Mollweide map filled ~480 of its pane's 958 px (at 1366×768 before this
  // case: 208×104 px in a pane of 681×207). The map (its projected sphere, from the picture's
  // header) spans most of its pane's width and height at 1366×768 and
  // 1920×1080, the picture is shown at one picture pixel per CSS pixel (the server's text, at least
  // 12 px, stays so), and the page's labels over it are 12 px or more.
  async map_fill({ context, url }) {
    const page = await openUi(context, url);
    await page.click('#pcTabSlices');
    for (const [width, height] of [[1366, 768], [1920, 1080]]) {
      const at = `${width}×${height}`;
      await page.setViewportSize({ width, height });
      await page.waitForTimeout(500);
      await page.waitForFunction(() => {
        const h = window.__raypc.slices.map.header, img = document.getElementById('mapImage');
        return h && img.complete && Math.abs(h.width - img.getBoundingClientRect().width * devicePixelRatio) < 2;
      }, null, { timeout: 20000 }).catch(() => { throw new TestFailure(`${at}: no map picture of its pane's size`); });
      await page.waitForTimeout(500);
      const m = await page.evaluate(() => {
        const h = window.__raypc.slices.map.header, img = document.getElementById('mapImage').getBoundingClientRect();
        const pane = document.getElementById('mapImage').parentElement.getBoundingClientRect();
        const css = Math.min(img.width / h.width, img.height / h.height);
        // d3's Mollweide: x in ±2√2, y in ±√2 times the scale.
        const mapW = 4 * Math.SQRT2 * h.scale * css, mapH = 2 * Math.SQRT2 * h.scale * css;
        const left = img.left + (h.centre[0] - 2 * Math.SQRT2 * h.scale) * css;
        const labels = [...document.querySelectorAll('#mapMarks .graticuleLabel')].map((t) => t.getBoundingClientRect().height);
        const outside = [...document.querySelectorAll('#mapMarks .graticuleLabel')].filter((t) => {
          const r = t.getBoundingClientRect();
          return r.left < pane.left - 0.5 || r.right > pane.right + 0.5 || r.top < pane.top - 0.5 || r.bottom > pane.bottom + 0.5;
        }).map((t) => t.textContent);
        return { projection: h.projection, css, mapW, mapH, left, outside, pane: { x: pane.x, w: pane.width, h: pane.height }, panel: document.getElementById('slices').getBoundingClientRect().width,
          labelPx: labels.length ? Math.min(...labels) : 0, fontPx: Number(document.querySelector('#mapMarks .graticuleLabel')?.getAttribute('font-size') ?? 0) * css };
      });
      console.log(`  ${at}: map ${m.mapW.toFixed(0)}×${m.mapH.toFixed(0)} px in a pane of ${m.pane.w.toFixed(0)}×${m.pane.h.toFixed(0)} (panel ${m.panel.toFixed(0)}); labels ${m.fontPx.toFixed(1)} px`);
      check(m.projection === 'mollweide', `${at}: the map is ${m.projection}, the default is mollweide`);
      check(m.css > 0.97 && m.css < 1.03, `${at}: the picture is shown at ${m.css} CSS px per pixel`);
      // (the rest of the width is the colour bar beside the map; of the height, the title and the hint)
      check(m.mapW >= 0.55 * m.pane.w, `${at}: the map is ${m.mapW.toFixed(0)} px wide in a pane of ${m.pane.w.toFixed(0)}`);
      check(m.mapH >= 0.65 * m.pane.h, `${at}: the map is ${m.mapH.toFixed(0)} px high in a pane of ${m.pane.h.toFixed(0)}`);
      check(m.left >= m.pane.x - 1 && m.left + m.mapW <= m.pane.x + m.pane.w + 1, `${at}: the map (${m.left.toFixed(0)}–${(m.left + m.mapW).toFixed(0)}) is not inside its pane`);
      check(m.fontPx >= 12, `${at}: the graticule's labels are ${m.fontPx} px`);
      check(m.outside.length === 0, `${at}: the graticule's labels ${JSON.stringify(m.outside)} are cut by the pane's edge`);
      // The view's colour bar (item 8): its labels round values, apart, inside the bar, 12 px.
      const bar = await page.evaluate(() => [...document.querySelectorAll('#legends .legendLabels')].map((l) => {
        const box = l.getBoundingClientRect();
        return { box: [box.left, box.right], spans: [...l.querySelectorAll('span')].map((x) => { const r = x.getBoundingClientRect(); return { text: x.textContent, l: r.left, r: r.right, px: parseFloat(getComputedStyle(x).fontSize) }; }) };
      }));
      check(bar.length > 0, `${at}: no colour bar on the view`);
      for (const b of bar) {
        check(b.spans.length >= 2, `${at}: the colour bar labels ${JSON.stringify(b.spans.map((x) => x.text))}`);
        b.spans.forEach((x, i) => {
          check(x.px >= 12 && x.l >= b.box[0] - 0.5 && x.r <= b.box[1] + 0.5, `${at}: the colour bar's label '${x.text}' (${x.px} px) at ${x.l}–${x.r}, the bar ${b.box}`);
          if (i > 0) check(x.l - b.spans[i - 1].r >= 4, `${at}: the colour bar's labels '${b.spans[i - 1].text}' and '${x.text}' run together`);
        });
      }
      await page.screenshot({ path: `${process.env.RAYPC_SHOTS ?? '/tmp'}/map_fill_${width}x${height}.png` }).catch(() => {});
    }
    check(page.raypcErrors.length === 0, `page errors: ${page.raypcErrors.join(' | ')}`);
  },

  // Issue 47, the feature plots (item 5), at 1366×768 and 1920×1080, on a synthetic model with
  // sinking slabs (raypc synth): the flux within the selection is drawn on its own (right) axis and
  // spans most of the plot's height, not flat near zero under the whole shell's lines; the depths'
  // legend is under the plot, not written over its lines.
  async flux_plot({ context, url }) {
    const page = await openUi(context, url);
    await page.click('#presets button[data-preset="task1-slabs-660km"]');
    await waitConverged(page);
    await page.click('#featuresDetails summary');
    await page.waitForFunction(() => window.__raypc.featureAnswers.some((f) => f && f.flux), null, { timeout: 60000 })
      .catch(async () => { throw new TestFailure(`no features with a flux; note: ${await page.textContent('#featuresNote')}`); });
    const f = await page.evaluate(() => window.__raypc.featureAnswers.filter((x) => x && x.flux).at(-1));
    const sel = f.flux.steps.flatMap((s) => s.selectedDownKm3PerYr.map((v) => -v)), all = f.flux.steps.flatMap((s) => s.downKm3PerYr.map((v) => -v));
    const maxSel = Math.max(...sel), maxAll = Math.max(...all);
    console.log(`  downward flux: whole shell up to ${maxAll.toFixed(2)} km³/yr, within the selection up to ${maxSel.toFixed(3)} km³/yr`);
    check(maxSel > 0 && maxSel < 0.5 * maxAll, `the fixture does not show the case: the selection's flux ${maxSel} against the shell's ${maxAll}`);
    for (const [width, height] of [[1366, 768], [1920, 1080]]) {
      const at = `${width}×${height}`;
      await page.setViewportSize({ width, height });
      await page.waitForTimeout(800);
      await page.evaluate(() => document.getElementById('featuresFlux').scrollIntoView());
      const plot = await page.evaluate(() => {
        const svg = document.getElementById('featuresFlux');
        // The vertical axes' height: the plot's.
        const vertical = [...svg.querySelectorAll('.axis path.domain')].map((d) => d.getBoundingClientRect()).sort((a, b) => b.height - a.height)[0];
        const axis = { height: vertical.height };
        // How high above the time axis each dashed line reaches.
        const dashed = [...svg.querySelectorAll('path[stroke-dasharray]')].map((p) => vertical.bottom - p.getBoundingClientRect().top);
        return { axisHeight: axis.height, dashed, svgTexts: [...svg.querySelectorAll('text')].map((t) => t.textContent),
          keys: [...document.querySelectorAll('#featuresFluxNote .fluxKey')].map((k) => k.textContent.trim()),
          rightAxis: svg.querySelectorAll('.selectedAxis .tick').length };
      });
      check(plot.dashed.length === f.flux.depthsKm.length, `${at}: ${plot.dashed.length} dashed lines for ${f.flux.depthsKm.length} depths`);
      const tallest = Math.max(...plot.dashed);
      check(tallest > 0.4 * plot.axisHeight, `${at}: the flux within the selection reaches ${tallest.toFixed(1)} px up the plot's ${plot.axisHeight.toFixed(1)} px: flat near zero`);
      check(plot.rightAxis >= 2, `${at}: no axis for the flux within the selection`);
      check(!plot.svgTexts.some((t) => / km$/.test(t)), `${at}: depth labels written over the plot: ${JSON.stringify(plot.svgTexts)}`);
      check(f.flux.depthsKm.every((d) => plot.keys.some((k) => k.includes(`${d} km`))), `${at}: the legend under the plot reads ${JSON.stringify(plot.keys)}`);
      // Issue 47, item 8: titles and tick labels were cut ("volume [km³]"): every text of the
      // feature and selection plots lies inside its svg, at 12 px or more; the time–depth
      // picture's title fits it (render::fitTitle measures it), drawn at one picture pixel per CSS px
      // or more.
      await page.click('#featuresTable tr[data-track]');
      await page.waitForFunction(() => document.querySelector('#featuresTimeline .trackDepth'), null, { timeout: 10000 })
        .catch(() => { throw new TestFailure(`${at}: clicking a track drew no timeline`); });
      const clipped = await page.evaluate(() => {
        const out = [];
        for (const id of ['featuresTimeline', 'featuresFlux', 'statsTime', 'statsProfile']) {
          const svg = document.getElementById(id), box = svg.getBoundingClientRect();
          for (const t of svg.querySelectorAll('text')) {
            const r = t.getBoundingClientRect();
            if (!t.textContent || r.width === 0) continue;
            const size = parseFloat(getComputedStyle(t).fontSize);
            if (r.left < box.left - 0.5 || r.right > box.right + 0.5 || r.top < box.top - 0.5 || r.bottom > box.bottom + 0.5 || size < 12)
              out.push(`${id} '${t.textContent}' ${size} px at ${r.left.toFixed(0)}–${r.right.toFixed(0)} × ${r.top.toFixed(0)}–${r.bottom.toFixed(0)} in ${box.left.toFixed(0)}–${box.right.toFixed(0)} × ${box.top.toFixed(0)}–${box.bottom.toFixed(0)}`);
          }
        }
        return out;
      });
      check(clipped.length === 0, `${at}: texts cut or small: ${clipped.join('; ')}`);
    }
    check(page.raypcErrors.length === 0, `page errors: ${page.raypcErrors.join(' | ')}`);
  },
};

// Chromium context options per case (default: 1280x860 at devicePixelRatio 1).
const caseOptions = {
  resolution: { contextOptions: { viewport: { width: 1000, height: 700 }, deviceScaleFactor: 2 } },
  responsive: { sampleRows: 100000, limitMs: 150000 },
  distributed: { ranks: 2 },
  series: { netcdf: true },
  play: { sampleRows: 20000 },
  first_view: { contextOptions: { viewport: { width: 1920, height: 1080 } } },
  // Issue 47 asks for these at 1366x768 (the smallest screen it names).
  stalls: { contextOptions: { viewport: { width: 1366, height: 768 } } },
  preset_labels: { contextOptions: { viewport: { width: 1366, height: 768 } } },
  readout: { contextOptions: { viewport: { width: 1366, height: 768 } } },
  shell_labels: { contextOptions: { viewport: { width: 1366, height: 768 } } },
  compare: { pairSeeds: [1, 2], contextOptions: { viewport: { width: 1920, height: 1080 } } },
  parcoords_access: { contextOptions: { viewport: { width: 1366, height: 768 } } },
  empty_selection: { contextOptions: { viewport: { width: 1366, height: 768 } } },
  map_section: { contextOptions: { viewport: { width: 1366, height: 768 } } },
  play_lines: { contextOptions: { viewport: { width: 1366, height: 768 } }, sampleRows: 20000 },
  map_fill: { contextOptions: { viewport: { width: 1366, height: 768 } } },
  flux_plot: { contextOptions: { viewport: { width: 1366, height: 768 } }, limitMs: 150000 },
};

const body = cases[caseName];
if (!body) {
  console.error(`unknown case '${caseName}'; cases: ${Object.keys(cases).join(', ')}`);
  process.exit(2);
}
runCase(mode === 'gpu' ? `${caseName} (gpu)` : caseName, raypc, fixture, body, { ...(caseOptions[caseName] ?? {}), gpu: mode === 'gpu' });
