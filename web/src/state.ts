// The render state document (docs/state.md), its shareable URL form and file form.
// The UI keeps one RenderState and sends it whole; keys are exactly the server's, because the
// server parses strictly (an unknown key is an error).

export interface CameraState {
  azimuthDeg: number;
  elevationDeg: number;
  distanceKm: number;
  fovYDeg: number;
  targetKm: [number, number, number];
}
export interface Brush {
  name: string;
  min: number;
  max: number;
}
export interface PathlineFilter {
  name: string; // a line attribute column, e.g. "length"
  min: number;
  max: number;
}
// The "pathlines" object of state version 2 (docs/state.md).
export interface PathlineState {
  visible: boolean;
  radiusKm: number;
  window: number;
  colorBy: string; // "age" or a line attribute column
  colorMap: string | null;
  range: [number, number] | null;
  filterByBrushes: boolean;
  filters: PathlineFilter[];
  ambientOcclusion: boolean;
}
export const kPathlineDefaults: PathlineState = {
  visible: false, radiusKm: 12, window: 10, colorBy: 'age', colorMap: 'blue-white-red', range: null,
  filterByBrushes: true, filters: [], ambientOcclusion: true,
};

export interface RenderState {
  version: number;
  step: number;
  camera: CameraState;
  image: { width: number; height: number };
  color: {
    variable: string;
    colorMap: string;
    range: [number, number] | null;
    opacity: [number, number][];
    opacityUnitKm: number;
  };
  brushes: Brush[];
  level: number | 'auto';
  timeBudgetMs: number;
  passes: number;
  pathlines?: PathlineState; // version 2 only
  [key: string]: unknown; // stepFactor, depthOpacity, core, shading, background: passed through
}

// Versions this UI reads; it writes the version of the server's default state (1: no pathlines).
export const kStateVersions = [1, 2];

export function cloneState(s: RenderState): RenderState {
  return JSON.parse(JSON.stringify(s));
}

// Fills keys missing from `s` with the defaults (the server's default state, whose version the
// result takes); throws on something that is not a state document, naming what is wrong. A version-1
// document has no pathlines; a version-2 one for a server that reads only version 1 is refused.
export function normaliseState(s: unknown, defaults: RenderState): RenderState {
  if (typeof s !== 'object' || s === null || Array.isArray(s)) throw new Error('state: expected a JSON object');
  const o = s as Record<string, unknown>;
  if (!kStateVersions.includes(o.version as number))
    throw new Error(`state: version ${JSON.stringify(o.version)}, expected one of ${kStateVersions.join(', ')}`);
  if ((o.version as number) > defaults.version)
    throw new Error(`state: version ${o.version as number}, but the server reads version ${defaults.version}`);
  if (o.version === 1 && 'pathlines' in o) throw new Error('state: pathlines: unknown key in a version 1 document');
  const out = cloneState(defaults) as Record<string, unknown>;
  for (const [k, v] of Object.entries(o)) {
    if (k === 'version') continue;
    const d = out[k];
    if (k === 'pathlines') out[k] = checkPathlines(v, (d as PathlineState | undefined) ?? kPathlineDefaults);
    else if (d && typeof d === 'object' && !Array.isArray(d) && v && typeof v === 'object' && !Array.isArray(v))
      out[k] = { ...(d as object), ...(v as object) };
    else out[k] = v;
  }
  out.version = defaults.version;
  if (defaults.version >= 2 && !out.pathlines) out.pathlines = { ...kPathlineDefaults, filters: [] };
  const r = out as RenderState;
  if (!Array.isArray(r.brushes)) throw new Error('state: brushes: expected an array');
  if (!r.camera || typeof r.camera.azimuthDeg !== 'number') throw new Error('state: camera: expected an object');
  return r;
}

// The pathlines object with defaults for missing keys; throws naming the key for an unknown key or a
// wrong type (the server checks ranges).
export function checkPathlines(v: unknown, defaults: PathlineState): PathlineState {
  if (typeof v !== 'object' || v === null || Array.isArray(v)) throw new Error('state: pathlines: expected an object');
  const out = { ...defaults, filters: defaults.filters.map((f) => ({ ...f })) } as unknown as Record<string, unknown>;
  const types: Record<string, (x: unknown) => boolean> = {
    visible: (x) => typeof x === 'boolean',
    radiusKm: (x) => typeof x === 'number',
    window: (x) => Number.isInteger(x),
    colorBy: (x) => typeof x === 'string',
    colorMap: (x) => x === null || typeof x === 'string',
    range: (x) => x === null || (Array.isArray(x) && x.length === 2 && x.every((y) => typeof y === 'number')),
    filterByBrushes: (x) => typeof x === 'boolean',
    filters: (x) => Array.isArray(x) && x.every((f) => f && typeof f === 'object' && typeof f.name === 'string' &&
      typeof f.min === 'number' && typeof f.max === 'number' && Object.keys(f).every((k) => ['name', 'min', 'max'].includes(k))),
    ambientOcclusion: (x) => typeof x === 'boolean',
  };
  for (const [k, x] of Object.entries(v as Record<string, unknown>)) {
    const ok = types[k];
    if (!ok) throw new Error(`state: pathlines.${k}: unknown key`);
    if (!ok(x)) throw new Error(`state: pathlines.${k}: unexpected value ${JSON.stringify(x).slice(0, 60)}`);
    out[k] = k === 'filters' ? (x as PathlineFilter[]).map((f) => ({ name: f.name, min: f.min, max: f.max })) : x;
  }
  return out as unknown as PathlineState;
}

// base64url of the UTF-8 JSON, for `#state=…`.
export function encodeStateForUrl(s: RenderState): string {
  const bytes = new TextEncoder().encode(JSON.stringify(s));
  let bin = '';
  for (const b of bytes) bin += String.fromCharCode(b);
  return btoa(bin).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
}

export function decodeStateFromUrl(text: string): unknown {
  const b64 = text.replace(/-/g, '+').replace(/_/g, '/');
  const bin = atob(b64 + '==='.slice((b64.length + 3) % 4));
  const bytes = Uint8Array.from(bin, (c) => c.charCodeAt(0));
  return JSON.parse(new TextDecoder().decode(bytes));
}

export function stateFromHash(hash: string): unknown | null {
  const m = /(?:^#|&)state=([A-Za-z0-9_-]+)/.exec(hash);
  return m ? decodeStateFromUrl(m[1]) : null;
}
