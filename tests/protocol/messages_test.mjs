// Every message the server sends matches its one description (src/server/protocol_schema.cpp,
// `raypc protocol-schema`), from which the UI's types are generated: a key the server adds, drops
// or retypes without its description fails here (and the UI's type check then sees the change).
// Starts `raypc serve` on the contest-layout fixture (preprocessed with pathlines) and asks every
// HTTP endpoint and the WebSocket for each kind of answer: frames with pathlines, reference shells
// and stereo, errors, pong and link included. Each answer is validated with ajv against its
// definition; every definition the server sends must have been seen. The client messages the test
// sends are checked against their definitions before the server accepts them, and one the schema
// refuses (an unknown key) the server refuses too.
//
// node --experimental-websocket messages_test.mjs RAYPC FIXTURE_DIR EXAMPLES_DIR
import { spawn, spawnSync } from 'node:child_process';
import { copyFileSync, cpSync, mkdirSync, mkdtempSync, readdirSync, rmSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { binaryHeader } from '../browser/harness.mjs';

const [raypc, fixture, examples] = process.argv.slice(2);
const repoRoot = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const require = createRequire(join(repoRoot, 'web', 'package.json'));
const Ajv = require('ajv');

const failures = [];
const fail = (message) => { failures.push(message); console.error(`FAIL: ${message}`); };

const schemaRun = spawnSync(raypc, ['protocol-schema'], { encoding: 'utf8' });
if (schemaRun.status !== 0) throw new Error(`raypc protocol-schema failed (${schemaRun.status}): ${schemaRun.stderr}`);
const schema = JSON.parse(schemaRun.stdout);
const ajv = new Ajv({ strict: true, allErrors: true, allowUnionTypes: true });
ajv.addKeyword('tsType');
ajv.addKeyword('x-carrier');
ajv.addSchema(schema, 'protocol');
const definitions = Object.keys(schema.definitions);
const seen = new Set();

// Checks `value` against the definition `name`; `where` says which answer it was.
function expectMessage(name, value, where) {
  const validate = ajv.getSchema(`protocol#/definitions/${name}`);
  if (!validate) return fail(`${where}: no definition '${name}' in the protocol schema`);
  seen.add(name);
  if (!validate(value))
    fail(`${where} does not match ${name}: ${ajv.errorsText(validate.errors, { dataVar: name })}; value: ${JSON.stringify(value).slice(0, 400)}`);
}

const headerOf = (buffer) => binaryHeader(buffer).header;

const tmp = mkdtempSync(join(tmpdir(), 'raypc-messages-'));
let server = null;
const watchdog = setTimeout(() => { fail('took longer than 150 s'); finish(); }, 150000);

async function finish() {
  clearTimeout(watchdog);
  if (server && server.exitCode === null) server.kill('SIGKILL');
  rmSync(tmp, { recursive: true, force: true });
  if (failures.length) {
    console.error(`${failures.length} failure(s)`);
    process.exit(1);
  }
  console.log(`ok: ${seen.size} message definitions matched by the server's answers: ${[...seen].sort().join(', ')}`);
  process.exit(0);
}

try {
  const dataset = join(tmp, 'ds');
  const pre = spawnSync(raypc, ['preprocess', fixture, '-o', dataset, '--quiet', '--sample-rows', '2000'], { encoding: 'utf8', timeout: 120000 });
  if (pre.status !== 0) throw new Error(`raypc preprocess failed (${pre.status}): ${pre.stderr}`);
  // The repository's example states and one with a variable the fixture lacks (`unavailable`).
  const exampleDir = join(tmp, 'examples');
  mkdirSync(exampleDir);
  for (const f of readdirSync(examples).filter((f) => f.endsWith('.json'))) copyFileSync(join(examples, f), join(exampleDir, f));
  writeFileSync(join(exampleDir, 'not-for-this-dataset.json'), JSON.stringify({ version: 9, brushes: [{ name: 'pressure', min: 0, max: 1 }] }));
  server = spawn(raypc, ['serve', dataset, '--port', '0', '--examples', exampleDir], { stdio: ['ignore', 'pipe', 'pipe'] });
  const base = await new Promise((resolveUrl, reject) => {
    let out = '', err = '';
    server.stdout.on('data', (d) => { out += d; const m = /(http:\/\/127\.0\.0\.1:\d+\/)/.exec(out); if (m) resolveUrl(m[1]); });
    server.stderr.on('data', (d) => { err += d; });
    server.on('exit', (code) => reject(new Error(`raypc serve exited with ${code}: ${err}`)));
  });
  const get = async (path, init) => {
    const r = await fetch(new URL(path, base), init);
    return { status: r.status, type: r.headers.get('content-type') ?? '', body: Buffer.from(await r.arrayBuffer()) };
  };
  const getJson = async (path, init, status = 200) => {
    const r = await get(path, init);
    if (r.status !== status) throw new Error(`${path}: status ${r.status}, expected ${status}: ${r.body.toString().slice(0, 300)}`);
    return JSON.parse(r.body.toString('utf8'));
  };
  const post = (body) => ({ method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });

  // ---- HTTP ----
  const info = await getJson('api/info');
  expectMessage('Info', info, 'GET /api/info');
  const state = info.defaultState;
  const variable = info.variables[0].name;
  expectMessage('Histogram', await getJson(`api/histogram?step=0&var=${encodeURIComponent(variable)}`), 'GET /api/histogram');
  // The spectrum of the shown depth: the fixture's analytic temperature anomaly on its 36 x 72 grid (Fejér's first rule).
  const spectrum = await getJson('api/spectrum?depthKm=660&lmax=8', post({ ...state, color: { ...state.color, variable: 'temperature anomaly' } }));
  expectMessage('Spectrum', spectrum, 'POST /api/spectrum');
  if (spectrum.power.length !== 9 || spectrum.quadrature !== "Fejér's first rule" || !(spectrum.power.slice(1).some((p) => p > 0)))
    fail(`POST /api/spectrum: ${JSON.stringify(spectrum)}`);

  // A pair's correlation per depth (POST /api/correlate), from a second server serving the dataset
  // and a copy of it as a pair: the same field, so r = 1 and the RMS ratio 1 on every shell.
  {
    const copy = join(tmp, 'ds-copy');
    cpSync(dataset, copy, { recursive: true });
    rmSync(join(copy, '.lock'), { force: true });
    const pairServer = spawn(raypc, ['serve', dataset, copy, '--port', '0'], { stdio: ['ignore', 'pipe', 'pipe'] });
    try {
      const pairBase = await new Promise((resolveUrl, reject) => {
        let out = '', err = '';
        pairServer.stdout.on('data', (d) => { out += d; const m = /(http:\/\/127\.0\.0\.1:\d+\/)/.exec(out); if (m) resolveUrl(m[1]); });
        pairServer.stderr.on('data', (d) => { err += d; });
        pairServer.on('exit', (code) => reject(new Error(`raypc serve A B exited with ${code}: ${err}`)));
      });
      const r = await fetch(new URL('api/correlate', pairBase), post({ ...state, color: { ...state.color, variable: 'temperature anomaly' } }));
      const corr = JSON.parse(Buffer.from(await r.arrayBuffer()).toString('utf8'));
      if (r.status !== 200) fail(`POST /api/correlate on a pair: status ${r.status}: ${JSON.stringify(corr)}`);
      else {
        expectMessage('PairCorrelation', corr, 'POST /api/correlate');
        const bad = corr.shells.filter((x) => x.correlation === null || Math.abs(x.correlation - 1) > 1e-9 || Math.abs(x.rmsRatio - 1) > 1e-9);
        if (corr.shells.length === 0 || bad.length) fail(`POST /api/correlate of a dataset with its copy: shells not r = 1: ${JSON.stringify(bad.slice(0, 3))}`);
      }
    } finally {
      pairServer.kill('SIGKILL');
    }
  }
  expectMessage('Selection', await getJson('api/selection', post({ ...state, brushes: [{ name: variable, min: info.variables[0].min, max: info.variables[0].mean }] })), 'POST /api/selection');
  expectMessage('SeriesProgress', await getJson('api/progress'), 'GET /api/progress');
  const presets = await getJson('api/presets');  // the fixture's examples, one not for it (below)
  if (!presets.some((p) => p.unavailable)) fail('GET /api/presets: the preset for another dataset is not unavailable');
  expectMessage('Presets', presets, 'GET /api/presets');
  expectMessage('SelectionOverTime', await getJson('api/stats?level=0', post({ ...state, brushes: [{ name: 'depth', min: 500, max: 1500 }] })), 'POST /api/stats');
  expectMessage('SelectionOverTime', await getJson('api/stats?level=0&profiles=all', post({ ...state, brushes: [{ name: 'depth', min: 500, max: 1500 }] })), 'POST /api/stats?profiles=all');
  const caps = { ...state, brushes: [{ name: 'depth', min: 0, max: 660 }, { name: 'lat', min: -90, max: -60 }, { name: 'lat', min: 60, max: 90 }],
    features: { ...state.features, depthsKm: [300, 660], bandHalfWidthKm: 100 } };
  const features = await getJson('api/features?job=protocol-test_1', post(caps));
  if (!features.tracks.some((t) => t.stalls.length)) fail('POST /api/features: no stall to check the shape of');
  expectMessage('FeatureSeries', features, 'POST /api/features');
  const job = await getJson('api/job-progress?job=protocol-test_1');
  if (job.state !== 'done' || job.done !== features.steps.length || job.total !== features.steps.length)
    fail(`GET /api/job-progress after the features: ${JSON.stringify(job)}`);
  expectMessage('JobProgress', job, 'GET /api/job-progress');
  const unknownJob = await getJson('api/job-progress?job=never-asked');
  if (unknownJob.state !== 'unknown') fail(`GET /api/job-progress of an id never given: ${JSON.stringify(unknownJob)}`);
  const picture = await get('api/time-depth?of=selected-mean&var=temperature&width=400&height=240', post(caps));
  if (picture.status !== 200 || picture.type !== 'image/png' || picture.body.readUInt32BE(16) !== 400)
    fail(`POST /api/time-depth: status ${picture.status}, ${picture.type}, ${picture.body.length} bytes`);
  const table = await get('api/time-depth?format=csv&var=temperature', post(caps));
  if (table.status !== 200 || !table.type.startsWith('text/csv') || !table.body.toString().startsWith('step,time_myr,radius_km,depth_km,selected_volume_km3,shell_volume_km3,selected_percent_of_shell,temperature selected mean ['))
    fail(`POST /api/time-depth?format=csv: status ${table.status}, ${table.type}, ${table.body.toString().slice(0, 200)}`);
  const lines = await get('api/pathlines?step=1&window=2');
  if (lines.status !== 200) fail(`GET /api/pathlines: status ${lines.status}: ${lines.body.toString().slice(0, 200)}`);
  else expectMessage('PathlinesHeader', headerOf(lines.body), 'GET /api/pathlines header');
  expectMessage('PersistenceDiagram', await getJson('api/persistence?step=0&top=5'), 'GET /api/persistence (stored seeding)');
  expectMessage('PersistenceDiagram', await getJson(`api/persistence?step=0&top=0&var=${encodeURIComponent(info.variables.at(-1).name)}`), 'GET /api/persistence (another variable)');
  const small = { ...state, image: { width: 320, height: 180 } };
  for (const projection of ['mollweide', 'orthographic']) {
    const map = await get('api/slice?view=map', post({ ...small, map: { ...state.map, projection } }));
    if (map.status !== 200) fail(`POST /api/slice?view=map: status ${map.status}`);
    else expectMessage('MapHeader', headerOf(map.body), `POST /api/slice?view=map (${projection}) header`);
  }
  const section = await get('api/slice?view=section', post(small));
  if (section.status !== 200) fail(`POST /api/slice?view=section: status ${section.status}: ${section.body.toString().slice(0, 300)}`);
  else expectMessage('SectionHeader', headerOf(section.body), 'POST /api/slice?view=section header');
  expectMessage('ProbeAnswer', await getJson('api/probe?step=0&lat=10&lon=-20&depthKm=1000'), 'GET /api/probe');
  expectMessage('ProbeAnswer', await getJson(`api/probe?step=0&lat=90&lon=180&depthKm=660&var=${encodeURIComponent(variable)}`), 'GET /api/probe (pole, one variable)');
  expectMessage('LinkedState', await getJson('api/link'), 'GET /api/link at start');
  for (const [path, init] of [['api/histogram?step=99&var=x', undefined], ['api/probe?step=0&lat=95&lon=0&depthKm=100', undefined],
    ['api/selection', post({ ...state, brushes: [{ name: 'pressure', min: 0, max: 1 }] })],
    ['api/features', post(state)], ['api/time-depth?of=mean', post(caps)], ['api/time-depth?of=shell-mean', post(caps)],
    ['api/time-depth?width=100000&height=100000', post(caps)], ['api/features?sigmas=-1', post(caps)],
    ['api/features?level=9', post(caps)], ['api/features?job=a%20b', post(caps)], ['api/job-progress'], ['api/job-progress?job=' + 'x'.repeat(65)], ['api/time-depth?format=gif', post(caps)], ['api/spectrum?lmax=999', post(caps)], ['api/spectrum?depthKm=5000', post(caps)], ['api/time-depth?of=selected-mean&var=pressure', post(caps)]])
    expectMessage('HttpError', await getJson(path, init, 400), `${path} (refused)`);

  // ---- WebSocket ----
  const wsUrl = new URL('ws', base);
  wsUrl.protocol = 'ws:';
  const ws = new WebSocket(wsUrl);
  ws.binaryType = 'arraybuffer';
  const texts = [], frames = [];
  let wake = () => {};
  ws.onmessage = (e) => {
    if (typeof e.data === 'string') texts.push(JSON.parse(e.data));
    else frames.push(headerOf(Buffer.from(e.data)));
    wake();
  };
  await new Promise((r, reject) => { ws.onopen = r; ws.onerror = () => reject(new Error('the WebSocket did not open')); });
  const until = async (what, condition, ms = 30000) => {
    const end = Date.now() + ms;
    while (!condition()) {
      if (Date.now() > end) throw new Error(`WebSocket: no ${what} within ${ms} ms`);
      await new Promise((r) => { wake = r; setTimeout(r, 200); });
    }
  };
  const send = (name, message) => {
    expectMessage(name, message, `the test's ${name}`);
    ws.send(JSON.stringify(message));
  };
  send('ClientHello', { type: 'hello', protocol: info.protocol });
  await until('hello', () => texts.some((m) => m.type === 'hello'));
  send('ClientPing', { type: 'ping', id: 7 });
  await until('pong', () => texts.some((m) => m.type === 'pong'));
  // A message the schema refuses is refused by the server too.
  const extra = { type: 'ping', id: 8, colour: 'red' };
  if (ajv.getSchema('protocol#/definitions/ClientPing')(extra)) fail('ClientPing accepts an unknown key');
  ws.send(JSON.stringify(extra));
  await until('error for an unknown key', () => texts.some((m) => m.type === 'error'));
  const frameStates = [
    ['plain', { ...small, passes: 2 }, 'still'],
    ['pathlines, shells, stereo', { ...small, passes: 1, step: 1, pathlines: { ...state.pathlines, visible: true },
      reference: { ...state.reference, shells: { ...state.reference.shells, visible: true } },
      stereo: { ...state.stereo, mode: 'anaglyph' } }, 'still'],
    ['interactive', { ...small }, 'interactive'],
    ['playback', { ...small, step: 2 }, 'playback'],
  ];
  let id = 100;
  for (const [what, s, mode] of frameStates) {
    const stateId = ++id;
    send('ClientState', { type: 'state', id: stateId, state: s, interactive: mode === 'interactive', playback: mode === 'playback' });
    await until(`converged frame of the ${what} state`, () => frames.some((f) => f.id === stateId && f.converged));
  }
  send('ClientCancel', { type: 'cancel' });
  send('ClientState', { type: 'state', id: ++id, state: { ...small, brushes: [{ name: 'pressure', min: 0, max: 1 }] } });
  await until('error for a bad state', () => texts.some((m) => m.type === 'error' && m.id === id));
  const set = await getJson('api/link', post({ state: small }));
  expectMessage('LinkSet', set, 'POST /api/link');
  await until('link message', () => texts.some((m) => m.type === 'link'));
  expectMessage('LinkedState', await getJson('api/link'), 'GET /api/link after a program set it');
  ws.close();

  const byType = { hello: 'ServerHello', error: 'ServerError', pong: 'ServerPong', link: 'ServerLink' };
  for (const m of texts) {
    if (!byType[m.type]) fail(`WebSocket: a text message of unknown type '${m.type}'`);
    else expectMessage(byType[m.type], m, `WebSocket '${m.type}' message`);
  }
  for (const f of frames) expectMessage('FrameHeader', f, `frame ${f.id} pass ${f.pass}`);
  for (const [key, what] of [['pathlines', 'pathlines'], ['shellKey', 'reference shells'], ['stereo', 'stereo']])
    if (!frames.some((f) => f[key] !== undefined)) fail(`no frame had '${key}' (${what} shown): that part of FrameHeader went unchecked`);
  if (!frames.some((f) => f.selection === null) || !frames.some((f) => f.selection)) fail('frames did not show both a null and a computed selection');

  // Every message the server sends was seen (the client's are the test's own, checked above).
  for (const name of definitions) {
    const carrier = schema.definitions[name]['x-carrier'];
    if (carrier && !seen.has(name)) fail(`${name} (${carrier}) was never received or sent, so never checked`);
  }
} catch (e) {
  fail(e.message);
}
await finish();
