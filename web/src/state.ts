// The render state document (docs/state.md), its shareable URL form and file form.
// Its types and its validator are generated (web/build.mjs) from the JSON Schema that raypc derives
// from the one description of the document (src/state/state_schema.cpp), so the UI checks a loaded
// document as strictly as the server parses it (an unknown key is an error) and keeps no copy of it.
import type { ErrorObject, ValidateFunction } from 'ajv';
import schema from './generated/state.schema.json';
import validateGenerated from './generated/validate_state';
import type { RenderState } from './generated/state_types';

export type { Brush, CameraState, PathlineFilter, PathlineState, RenderState, StereoState } from './generated/state_types';

const validateDocument = validateGenerated as unknown as ValidateFunction;

// Versions this UI reads; it writes the version of the server's default state.
export const kStateVersions: number[] = schema.properties.version.enum;

// The ranges of each brushed name (brushes, pathlines.filters), in the order the names first appear.
// A name that repeats adds a range to its axis: a value is selected when it lies in one of them (OR
// within an axis, AND over axes), as raypc resolves them (analysis/selection.h).
export function rangesByName(ranges: readonly { name: string; min: number; max: number }[]): Map<string, [number, number][]> {
  const out = new Map<string, [number, number][]>();
  for (const r of ranges) {
    const list = out.get(r.name) ?? [];
    list.push([r.min, r.max]);
    out.set(r.name, list);
  }
  return out;
}

export function inRanges(v: number, ranges: readonly [number, number][]): boolean {
  return ranges.some(([lo, hi]) => v >= lo && v <= hi);
}

export function cloneState(s: RenderState): RenderState {
  return JSON.parse(JSON.stringify(s));
}

// A copy of `defaults` with the keys of `s` merged in (objects key by key, anything else replaced),
// after checking `s` against the schema; the result takes the defaults' version (the server's default
// state). Throws an Error naming the key for anything the schema refuses. A version-1 document has no
// pathlines, and one newer than the server reads is refused. The server checks the rest (min <= max
// and ascending opacity positions, which JSON Schema cannot express; names against the dataset).
export function normaliseState(s: unknown, defaults: RenderState): RenderState {
  if (typeof s !== 'object' || s === null || Array.isArray(s)) throw new Error('state: expected a JSON object');
  const version = (s as Record<string, unknown>).version;
  const newest = Math.max(...kStateVersions);
  if (version === undefined) throw new Error(`state: version: missing; expected ${newest}`);
  if (!kStateVersions.includes(version as number))
    throw new Error(`state: version: ${JSON.stringify(version)} is not supported, expected one of ${kStateVersions.join(', ')}`);
  if ((version as number) > defaults.version)
    throw new Error(`state: version ${version as number}, but the server reads version ${defaults.version}`);
  if (!validateDocument(s)) throw new Error(`state: ${describeError(validateDocument.errors ?? [], s)}`);
  const out = merge(cloneState(defaults) as unknown as Record<string, unknown>, s as Record<string, unknown>) as unknown as RenderState;
  out.version = defaults.version;
  return out;
}

function isObject(x: unknown): x is Record<string, unknown> {
  return typeof x === 'object' && x !== null && !Array.isArray(x);
}

function merge(base: Record<string, unknown>, over: Record<string, unknown>): Record<string, unknown> {
  for (const [k, v] of Object.entries(over)) {
    const b = base[k];
    base[k] = isObject(b) && isObject(v) ? merge(b, v) : JSON.parse(JSON.stringify(v));
  }
  return base;
}

// ---- messages: "pathlines.filters[0].max: missing", as the server words them where it can ----------

function unescapePointer(part: string): string {
  return part.replace(/~1/g, '/').replace(/~0/g, '~');
}

// "/brushes/0/min" -> "brushes[0].min"
function keyPath(pointer: string, key?: string): string {
  let out = '';
  for (const part of [...pointer.split('/').slice(1).map(unescapePointer), ...(key === undefined ? [] : [key])])
    out += /^\d+$/.test(part) ? `[${part}]` : (out ? '.' : '') + part;
  return out || 'top level';
}

function at(root: unknown, pointer: string): unknown {
  let x: unknown = root;
  for (const part of pointer.split('/').slice(1).map(unescapePointer)) x = (x as Record<string, unknown> | undefined)?.[part];
  return x;
}

function expectation(e: ErrorObject): string {
  const p = e.params as Record<string, unknown>;
  switch (e.keyword) {
    case 'type': return String(p.type).replace(/,/g, ' or ');
    case 'const': return JSON.stringify(p.allowedValue);
    case 'enum': return `one of ${(p.allowedValues as unknown[]).map((v) => JSON.stringify(v)).join(', ')}`;
    case 'minimum': case 'maximum': case 'exclusiveMinimum': case 'exclusiveMaximum':
      return `a number ${String(p.comparison)} ${String(p.limit)}`;
    case 'minItems': return `at least ${String(p.limit)} items`;
    case 'maxItems': return `at most ${String(p.limit)} items`;
    case 'minLength': return 'a non-empty string';
    case 'not': {
      const negated = (at(schema, e.schemaPath.slice(1)) as Record<string, unknown> | undefined)?.const;
      return `anything but ${JSON.stringify(negated)}`;
    }
    default: return e.message ?? e.keyword;
  }
}

function describeError(errors: ErrorObject[], doc: unknown): string {
  // Alternatives (anyOf, e.g. level) report each branch before themselves: name them all.
  const alternatives = errors.find((e) => e.keyword === 'anyOf');
  const e = alternatives ?? errors[0];
  if (!e) return 'not a valid state document';
  const p = e.params as Record<string, unknown>;
  if (e.keyword === 'additionalProperties') return `${keyPath(e.instancePath, String(p.additionalProperty))}: unknown key`;
  if (e.keyword === 'required') return `${keyPath(e.instancePath, String(p.missingProperty))}: missing`;
  const path = keyPath(e.instancePath);
  // A key newer than the document's version: {"not": {}, "description": "needs version N"}.
  const gate = e.keyword === 'not' ? at(schema, e.schemaPath.slice(1).replace(/\/not$/, '')) as Record<string, unknown> : null;
  if (gate && isObject(gate.not) && !Object.keys(gate.not).length)
    return `${path}: ${String(gate.description)}, the document says version ${JSON.stringify(at(doc, '/version'))}`;
  const expected = alternatives
    ? errors.filter((x) => x !== e && x.schemaPath.startsWith(e.schemaPath)).map(expectation).join(' or ')
    : expectation(e);
  return `${path}: expected ${expected}, found ${JSON.stringify(at(doc, e.instancePath))?.slice(0, 80)}`;
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
