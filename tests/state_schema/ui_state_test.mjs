// The state document has one description (src/state/state_schema.cpp); this test checks that the
// three things derived from it agree: raypc's parser (via state_cases), the JSON Schema
// (`raypc state-schema`) and the UI's loader (web/src/state.ts, bundled for node with esbuild and
// run on the schema's generated validator).
//   node ui_state_test.mjs RAYPC STATE_CASES DATASET WORK_DIR
// Cases: the server's default state round-trips through the UI's loader unchanged (also through
// the URL form and back through raypc); a state with every optional value set likewise; every
// examples/*.json and the example in docs/state.md are accepted by the schema, the UI and raypc;
// malformed documents are refused by all three naming the same key; and 400 random mutations of
// the default state are accepted or refused alike by raypc and the UI (apart from the three
// relations JSON Schema cannot express).
import { spawnSync } from 'node:child_process';
import { mkdirSync, readFileSync, readdirSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { isDeepStrictEqual } from 'node:util';

const [raypc, stateCases, dataset, work] = process.argv.slice(2);
const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const web = join(root, 'web');
mkdirSync(work, { recursive: true });
const failures = [];
const check = (ok, message) => { if (!ok) failures.push(message); };

function run(cmd, args) {
  const r = spawnSync(cmd, args, { encoding: 'utf8', maxBuffer: 1 << 28 });
  if (r.status !== 0) throw new Error(`${cmd} ${args.join(' ')} failed (${r.status}): ${r.stderr}${r.error ?? ''}`);
  return r.stdout;
}

// The schema the UI is built from is the one raypc writes now.
const schemaText = run(raypc, ['state-schema']);
const generatedText = readFileSync(join(web, 'src/generated/state.schema.json'), 'utf8');
if (schemaText !== generatedText)
  throw new Error('web/src/generated/state.schema.json differs from `raypc state-schema`: build raypc (cmake --build build)');
const schema = JSON.parse(schemaText);
run(process.execPath, [join(web, 'build.mjs'), '--generate']);

// The UI's loader, bundled as the page bundles it.
const require = createRequire(join(web, 'package.json'));
const fromWeb = (name) => {
  try {
    return require(name);
  } catch {
    throw new Error(`${name} is not installed in ${join(web, 'node_modules')}: run scripts/build-web.sh`);
  }
};
const { buildSync } = fromWeb('esbuild');
const bundle = join(work, 'state.mjs');
buildSync({ entryPoints: [join(web, 'src/state.ts')], bundle: true, format: 'esm', platform: 'node', outfile: bundle, logLevel: 'error' });
const ui = await import(pathToFileURL(bundle).href);
const Ajv = fromWeb('ajv');
const validate = new Ajv({ allowUnionTypes: true, strict: true }).compile(schema);

const uiLoad = (doc, defaults) => {
  try {
    return { ok: true, json: ui.normaliseState(doc, defaults) };
  } catch (e) {
    return { ok: false, error: e.message };
  }
};
let batch = 0;
const writeDocs = (docs) => {
  const file = join(work, `docs${batch++}.json`);
  writeFileSync(file, JSON.stringify(docs));
  return file;
};
const cppParse = (docs) => JSON.parse(run(stateCases, ['parse', writeDocs(docs)]));
// "state: brushes[0].min: min 3 is greater than max 1" -> "brushes[0].min"
const keyOf = (message) => /^state: (.*?): /.exec(message)?.[1] ?? `(no key in '${message}')`;
// The UI may name the element of a number array that raypc names as a whole: targetKm[1] / targetKm.
const sameKey = (a, b) => a === b || a.startsWith(`${b}[`) || b.startsWith(`${a}[`);
// Of several unknown keys in one object, raypc names the first in sorted order, the UI the first written.
// Of several keys newer than the document's version, raypc names the first in the description's
// order, the UI the first in sorted order (a version-1 document: camera.views vs axes); both say
// which version the key needs and the document's.
const versionGate = (m) => /: needs version \d+, the document says version (\d+)$/.exec(m)?.[1];
const sameError = (a, b) => sameKey(keyOf(a), keyOf(b)) ||
  (/: unknown key$/.test(a) && /: unknown key$/.test(b) && keyOf(a).replace(/\.[^.]*$/, '') === keyOf(b).replace(/\.[^.]*$/, '')) ||
  (versionGate(a) !== undefined && versionGate(a) === versionGate(b));
const same = (a, b) => JSON.stringify(a) === JSON.stringify(b);
// raypc stores most numbers as float; the UI keeps what the document says.
const sameAsFloats = (a, b) => isDeepStrictEqual(JSON.parse(JSON.stringify(a, (k, v) => (typeof v === 'number' ? Math.fround(v) : v))),
  JSON.parse(JSON.stringify(b, (k, v) => (typeof v === 'number' ? Math.fround(v) : v))));

// ---- the server's default state round-trips unchanged -----------------------------------------
const defaults = JSON.parse(run(stateCases, ['default', dataset]));
{
  check(validate(defaults), `the schema refuses the default state: ${JSON.stringify(validate.errors)}`);
  // The UI's types describe a complete document (web/build.mjs, completeSchema): toJson writes one.
  const { completeSchema } = await import(pathToFileURL(join(web, 'build.mjs')).href);
  const validateComplete = new Ajv({ allowUnionTypes: true, strict: true }).compile(completeSchema(schema));
  for (const doc of [defaults, JSON.parse(run(stateCases, ['parse', writeDocs([{ version: 1 }])]))[0].json])
    check(validateComplete(doc), `toJson wrote a document that the UI's types do not describe: ${JSON.stringify(validateComplete.errors)}`);
  const loaded = uiLoad(defaults, defaults);
  check(loaded.ok && same(loaded.json, defaults), `default state through the UI's loader: ${JSON.stringify(loaded)}`);
  const viaUrl = uiLoad(ui.decodeStateFromUrl(ui.encodeStateForUrl(defaults)), defaults);
  check(viaUrl.ok && same(viaUrl.json, defaults), `default state through the URL form: ${JSON.stringify(viaUrl)}`);
  const [back] = cppParse([loaded.json]);
  check(back.ok && same(back.json, defaults), `default state loaded by the UI, parsed by raypc: ${JSON.stringify(back)}`);
}

// ---- a state with every optional value set round-trips unchanged ------------------------------
{
  const rich = structuredClone(defaults);
  Object.assign(rich, { step: 3, level: 1, timeBudgetMs: 80, passes: 4, stepFactor: 0.25, depthOpacity: 0.7, background: [0.1, 0.2, 0.3] });
  rich.camera.targetKm = [100, -200, 300];
  rich.color = { variable: 'temperature', colorMap: 'inferno', range: [1000, 3000], opacity: [[0, 0.1], [0.5, 0.9], [1, 0.2]], opacityUnitKm: 50,
    logScale: true, points: [[0, 0.1, 0.2, 0.3], [0.4, 0.5, 0.5, 0.5], [1, 0.9, 0.8, 0.7]], reversed: true };
  rich.legend = true;
  rich.reference = { shells: { visible: true, depthsKm: [660, 1600], opacity: 0.1, color: [0.5, 0.6, 0.7] },
    graticule: { visible: true, spacingDeg: 15, opacity: 0.25, color: [0.25, 0.5, 0.75] },
    coastlines: { visible: true, opacity: 0.5, color: [1, 1, 0] }, lineWidthPx: 2.5 };
  rich.brushes = [{ name: 'depth', min: 0, max: 660 }, { name: 'temperature', min: 1500, max: 2500 }, { name: 'depth', min: 1500, max: 2000 }];
  rich.axes = ['temperature', 'depth', 'radius'];
  rich.core = { visible: false, variable: 'temperature', color: [0.2, 0.3, 0.4], colorMap: 'grayscale', range: [2000, 4000] };
  rich.shading = { enabled: true, light: [-1, 0.5, 0.25], ambient: 0.2, diffuse: 0.8, specular: 0.5, shininess: 10, shadows: true, shadowStrength: 0.5 };
  rich.pathlines = { visible: true, radiusKm: 30, minWidthPx: 3, window: 5, colorBy: 'length', colorMap: 'cool-to-warm', range: [0, 5000],
    filterByBrushes: false, filters: [{ name: 'length', min: 100, max: 400 }, { name: 'length', min: 1000, max: 4000 }], ambientOcclusion: false };
  rich.stereo = { mode: 'anaglyph', eyeSeparationKm: 450, convergenceKm: 17000 };
  const [parsed] = cppParse([rich]);
  check(parsed.ok && sameAsFloats(parsed.json, rich), `raypc changed the rich state: ${JSON.stringify(parsed)}`);
  const loaded = uiLoad(parsed.json, defaults);
  check(loaded.ok && same(loaded.json, parsed.json), `the rich state through the UI's loader: ${JSON.stringify(loaded)}`);
}

// ---- every example (and docs/state.md's) is accepted by the schema, the UI and raypc alike -------
{
  const names = readdirSync(join(root, 'examples')).filter((f) => f.endsWith('.json')).sort();
  check(names.length > 0, 'no examples/*.json');
  const docs = names.map((f) => JSON.parse(readFileSync(join(root, 'examples', f), 'utf8')));
  const docExamples = [...readFileSync(join(root, 'docs/state.md'), 'utf8').matchAll(/```json\n([\s\S]*?)```/g)];
  check(docExamples.length > 0, 'docs/state.md has no ```json example');
  docExamples.forEach((m, i) => {
    names.push(`../docs/state.md (example ${i + 1})`);
    docs.push(JSON.parse(m[1]));
  });
  const loaded = docs.map((d) => uiLoad(d, defaults));
  const cpp = cppParse([...docs, ...loaded.map((l) => l.json ?? {})]);
  names.forEach((name, i) => {
    check(validate(docs[i]), `the schema refuses examples/${name}: ${JSON.stringify(validate.errors)}`);
    check(loaded[i].ok, `the UI refuses examples/${name}: ${loaded[i].error}`);
    check(cpp[i].ok, `raypc refuses examples/${name}: ${cpp[i].error}`);
    check(cpp[docs.length + i].ok, `raypc refuses examples/${name} as the UI loaded it: ${cpp[docs.length + i].error}`);
  });
  console.log(`${names.length} examples (with docs/state.md's) accepted by the schema, the UI and raypc`);
}

// ---- malformed documents are refused by all three, naming the same key -------------------------
{
  const v2 = (extra) => ({ version: 2, ...extra });
  const bad = [
    [v2({ camera: { zoom: 2 } }), 'camera.zoom'],
    [v2({ camera: { elevationDeg: 95 } }), 'camera.elevationDeg'],
    [v2({ color: { colorMap: 'rainbow' } }), 'color.colorMap'],
    [v2({ image: { width: 0 } }), 'image.width'],
    [v2({ level: 7 }), 'level'],
    [v2({ level: 'fine' }), 'level'],
    [v2({ brushes: [{ name: 'depth', min: 0 }] }), 'brushes[0].max'],
    [v2({ brushes: [{ name: '', min: 0, max: 1 }] }), 'brushes[0].name'],
    [v2({ shading: { light: [0, 0, 0] } }), 'shading.light'],
    [v2({ core: { color: [0, 0, 2] } }), 'core.color'],
    [v2({ pathlines: { visible: 'yes' } }), 'pathlines.visible'],
    [v2({ pathlines: { filters: [{ name: 'length', min: 1, max: 2, bogus: 1 }] } }), 'pathlines.filters[0].bogus'],
    [{ version: 1, pathlines: { visible: true } }, 'pathlines'],
    [{ version: 5, stereo: { mode: 'top-bottom' } }, 'stereo.mode'],
    [{ version: 5, stereo: { eyeSeparationKm: -1 } }, 'stereo.eyeSeparationKm'],
    [{ version: 4, stereo: { mode: 'anaglyph' } }, 'stereo'],
    [{ version: 6, shading: { shadowStrength: 1.5 } }, 'shading.shadowStrength'],
    [{ version: 6, shading: { shadows: 'yes' } }, 'shading.shadows'],
    [{ version: 5, shading: { shadows: true } }, 'shading.shadows'],
    [{ step: 1 }, 'version'],
    [{ version: 14 }, 'version'],
    [{ version: 12, pair: { dataset: 'b' } }, 'pair'],
    [{ version: 13, pair: { dataset: '' } }, 'pair.dataset'],
    [{ version: 13, pair: { steps: 'time' } }, 'pair.dataset'],
    [{ version: 13, pair: { dataset: 'b', steps: 'seconds' } }, 'pair.steps'],
    [{ version: 13, pair: { dataset: 'b', colour: 1 } }, 'pair.colour'],
    [{ version: 13, pair: 'b' }, 'pair'],
    [{ version: 10, features: { colorById: true } }, 'features.colorById'],
    [{ version: 11, features: { highlight: [0] } }, 'features.highlight'],
    [{ version: 11, features: { highlight: [1.5] } }, 'features.highlight'],
    [{ version: 11, features: { stallBy: 'deepest' } }, 'features.stallBy'],
    [{ version: 12, features: { stallBy: 'tip' } }, 'features.stallBy'],
    [{ version: 9, features: { level: 0 } }, 'features'],
    [{ version: 10, features: { level: 3 } }, 'features.level'],
    [{ version: 10, features: { depthsKm: [7000] } }, 'features.depthsKm'],
    [{ version: 8, map: { depthKm: 660 } }, 'map'],
    [{ version: 9, map: { projection: 'mercator' } }, 'map.projection'],
    [{ version: 9, map: { depthKm: -1 } }, 'map.depthKm'],
    [{ version: 9, section: { from: { latDeg: 95 } } }, 'section.from.latDeg'],
  ];
  const cpp = cppParse(bad.map(([d]) => d));
  bad.forEach(([doc, key], i) => {
    const what = JSON.stringify(doc);
    if (key !== 'version') check(!validate(doc), `the schema accepts ${what}`);
    const u = uiLoad(doc, defaults);
    check(!u.ok && sameKey(keyOf(u.error), key), `the UI on ${what}: ${u.error ?? 'accepted'}, expected a message naming ${key}`);
    check(!cpp[i].ok && keyOf(cpp[i].error) === key, `raypc on ${what}: ${cpp[i].error ?? 'accepted'}, expected a message naming ${key}`);
  });
  console.log(`${bad.length} malformed documents refused by the schema, the UI and raypc, naming the key`);
}

// ---- random mutations: raypc and the UI accept and refuse alike -------------------------------
{
  let seed = 12345;
  const random = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648);
  const pick = (xs) => xs[Math.floor(random() * xs.length)];
  const values = [null, true, false, 'x', '', 'auto', 'viridis', 'rainbow', 'age', 'depth', 0, 1, 2, -1, 0.5, 7, 179.95, 2.5e5,
    1e12, -1e12, [], [0, 0, 0], [1, 2, 3], [1, 2], [2, 1], [0, 0.5, 1.5], [[0, 0], [1, 1]], [[0.5, 0], [0.2, 1]], {},
    { name: 'depth', min: 0, max: 1 }, { name: 'depth', min: 2, max: 1 }, { name: 'depth', min: 0 }, { min: 0, max: 1 }];
  const paths = (x, prefix = []) => {
    const out = [prefix];
    if (x && typeof x === 'object') for (const [k, v] of Object.entries(x)) out.push(...paths(v, [...prefix, Array.isArray(x) ? Number(k) : k]));
    return out;
  };
  const base = structuredClone(defaults);
  base.brushes = [{ name: 'depth', min: 0, max: 1000 }];
  base.pathlines.filters = [{ name: 'length', min: 0, max: 10 }];
  const docs = [];
  for (let i = 0; i < 400; i++) {
    const doc = structuredClone(base);
    const all = paths(doc).filter((p) => p.length > 0);
    const path = pick(all);
    const parent = path.slice(0, -1).reduce((o, k) => o[k], doc);
    const key = path[path.length - 1];
    const op = random();
    if (op < 0.7) parent[key] = structuredClone(pick(values));
    else if (op < 0.8 && !Array.isArray(parent)) delete parent[key];
    else if (op < 0.9) {
      const objects = paths(doc).map((p) => p.reduce((o, k) => o[k], doc)).filter((o) => o && typeof o === 'object' && !Array.isArray(o));
      pick(objects).bogus = 1;
    } else {
      doc.version = 1;
      if (random() < 0.5) delete doc.pathlines;
    }
    docs.push(doc);
  }
  const cpp = cppParse(docs);
  // What JSON Schema cannot express; raypc alone refuses these.
  const onlyRaypc = /is greater than max|with min < max|positions must ascend|a second range on/;
  let refused = 0, raypcOnly = 0;
  docs.forEach((doc, i) => {
    const u = uiLoad(doc, defaults), c = cpp[i];
    const what = JSON.stringify(doc).slice(0, 300);
    if (!c.ok && onlyRaypc.test(c.error)) {
      raypcOnly++;
      check(u.ok, `the UI refuses what only raypc should (${c.error}): ${u.error}`);
      return;
    }
    refused += c.ok ? 0 : 1;
    check(u.ok === c.ok, `raypc ${c.ok ? 'accepts' : `refuses (${c.error})`} but the UI ${u.ok ? 'accepts' : `refuses (${u.error})`}: ${what}`);
    if (!u.ok && !c.ok) check(sameError(u.error, c.error), `raypc and the UI name different keys: '${c.error}' vs '${u.error}'`);
  });
  check(refused > 100 && refused < 380, `${refused} of 400 mutations refused: the mutations do not exercise both outcomes`);
  console.log(`400 mutations: ${refused} refused by both with the same key, ${raypcOnly} refused by raypc alone (min/max order), the rest accepted by both`);
}

if (failures.length) {
  for (const f of failures) console.error(`FAIL: ${f}`);
  process.exit(1);
}
console.log('ok');
