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
  [key: string]: unknown; // stepFactor, depthOpacity, core, shading, background: passed through
}

export const kStateVersion = 1;

export function cloneState(s: RenderState): RenderState {
  return JSON.parse(JSON.stringify(s));
}

// Fills keys missing from `s` with the defaults (both documents of this version); throws on
// something that is not a state document, naming what is wrong.
export function normaliseState(s: unknown, defaults: RenderState): RenderState {
  if (typeof s !== 'object' || s === null || Array.isArray(s)) throw new Error('state: expected a JSON object');
  const o = s as Record<string, unknown>;
  if (o.version !== kStateVersion) throw new Error(`state: version ${JSON.stringify(o.version)}, expected ${kStateVersion}`);
  const out = cloneState(defaults) as Record<string, unknown>;
  for (const [k, v] of Object.entries(o)) {
    const d = out[k];
    if (d && typeof d === 'object' && !Array.isArray(d) && v && typeof v === 'object' && !Array.isArray(v))
      out[k] = { ...(d as object), ...(v as object) };
    else out[k] = v;
  }
  const r = out as RenderState;
  if (!Array.isArray(r.brushes)) throw new Error('state: brushes: expected an array');
  if (!r.camera || typeof r.camera.azimuthDeg !== 'number') throw new Error('state: camera: expected an object');
  return r;
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
