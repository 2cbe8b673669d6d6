// HTTP side of docs/protocol.md: dataset info, histograms, the parallel-coordinates sample,
// exact selection volumes and screenshots. Every function throws an Error naming the endpoint
// and the server's message on a non-2xx answer.
import type { RenderState } from './state';

// The server's answers are typed from their one description (src/server/protocol_schema.cpp,
// `raypc protocol-schema`, generated into generated/protocol_types.ts).
import type {
  CoordinateInfo, FeatureSeries, FeatureTrack, Histogram, Info, JobProgress, MapHeader, PathlinesHeader, PersistenceDiagram, PersistencePair, Preset,
  ProbeAnswer, SectionHeader, Selection, SelectionOverTime, SeriesProgress, Spectrum, StepInfo, VariableInfo, PairCorrelation,
} from './generated/protocol_types';
export type {
  CoordinateInfo, FeatureSeries, FeatureTrack, Histogram, Info, JobProgress, PersistenceDiagram, PersistencePair, Preset, ProbeAnswer, Selection,
  SelectionOverTime, SeriesProgress, Spectrum, StepInfo, VariableInfo, PairCorrelation,
};
// What POST /api/slice drew: a map's projection or a section's plot (`view` tells which).
export type SliceHeader = MapHeader | SectionHeader;
export interface Sample {
  rows: number;
  columns: string[];
  values: Float32Array; // rows x columns, row-major
}

async function check(response: Response, what: string): Promise<Response> {
  if (response.ok) return response;
  let message = `${response.status} ${response.statusText}`;
  try {
    const body = await response.json();
    if (body && typeof body.error === 'string') message = body.error;
  } catch {
    // not JSON: keep the status line
  }
  throw new Error(`${what}: ${message}`);
}

// `dataset`: a pair's second dataset is 1 (docs/compare.md).
export async function fetchInfo(dataset = 0): Promise<Info> {
  return (await check(await fetch(dataset ? `api/info?dataset=${dataset}` : 'api/info'), 'GET /api/info')).json();
}

// GET /api/progress (docs/protocol.md): a series of netCDF files preprocessed in the background
// while its first step is shown; 'complete' when the server shows a whole dataset.
export async function fetchProgress(): Promise<SeriesProgress> {
  return (await check(await fetch('api/progress', { cache: 'no-store' }), 'GET /api/progress')).json();
}

export async function fetchHistogram(step: number, variable: string): Promise<Histogram> {
  const url = `api/histogram?step=${step}&var=${encodeURIComponent(variable)}`;
  return (await check(await fetch(url), 'GET /api/histogram')).json();
}

// GET /api/sample (docs/protocol.md). 'variables' leaves out the coordinate columns, which are the
// same in every step (what a new step's sample changes). The body (megabytes) is fetched by a
// worker (sample_worker.ts): received on the page's main thread, such a body held it in long tasks
// during which the 3D frames of a playback waited (measured in docs/ui.md). Without workers, here.
type SampleColumns = 'all' | 'variables';

function sampleUrl(step: number, which: SampleColumns, dataset = 0): string {
  return `api/sample?step=${step}&columns=${which}${dataset ? `&dataset=${dataset}` : ''}`;
}

export async function fetchSampleBody(url: string): Promise<ArrayBuffer> {
  return (await check(await fetch(url), 'GET /api/sample')).arrayBuffer();
}

// What sample_worker.ts answers: the body (transferred, not copied) or the error's message.
export type SampleReply = { id: number; buffer: ArrayBuffer } | { id: number; error: string };

let sampleWorker: Worker | null | undefined;
const sampleRequests = new Map<number, { url: string; resolve: (b: ArrayBuffer) => void; reject: (e: Error) => void }>();
let sampleRequestId = 0;

// A worker that cannot start (its script not loaded, workers not allowed) leaves the fetching to
// the main thread, the requests it had included.
function fetchSampleOffThread(url: string): Promise<ArrayBuffer> {
  if (sampleWorker === undefined) {
    try {
      sampleWorker = new Worker('sample_worker.js');
      sampleWorker.onmessage = (e: MessageEvent<SampleReply>) => {
        const request = sampleRequests.get(e.data.id);
        sampleRequests.delete(e.data.id);
        if (request && 'buffer' in e.data) request.resolve(e.data.buffer);
        else if (request && 'error' in e.data) request.reject(new Error(e.data.error));
      };
      sampleWorker.onerror = () => {
        sampleWorker?.terminate();
        sampleWorker = null;
        for (const { url: u, resolve, reject } of sampleRequests.values()) fetchSampleBody(u).then(resolve, reject);
        sampleRequests.clear();
      };
    } catch {
      sampleWorker = null;
    }
  }
  if (!sampleWorker) return fetchSampleBody(url);
  const id = ++sampleRequestId, worker = sampleWorker;
  return new Promise((resolve, reject) => {
    sampleRequests.set(id, { url, resolve, reject });
    worker.postMessage({ id, url: new URL(url, document.baseURI).href });
  });
}

// `dataset`: a pair's second dataset is 1 (docs/compare.md).
export async function fetchSample(step: number, columns: string[], which: SampleColumns = 'all', dataset = 0): Promise<Sample> {
  const buffer = await fetchSampleOffThread(sampleUrl(step, which, dataset));
  if (buffer.byteLength % (4 * columns.length) !== 0)
    throw new Error(`GET /api/sample: ${buffer.byteLength} bytes is not a whole number of rows of ${columns.length} float32`);
  const values = new Float32Array(buffer);
  return { rows: values.length / columns.length, columns, values };
}

export async function postSelection(state: RenderState, signal?: AbortSignal): Promise<Selection> {
  const r = await fetch('api/selection', {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state), signal,
  });
  return (await check(r, 'POST /api/selection')).json();
}

export async function postScreenshot(state: RenderState): Promise<Blob> {
  const r = await fetch('api/screenshot', {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state),
  });
  return (await check(r, 'POST /api/screenshot')).blob();
}

export async function fetchPresets(): Promise<Preset[]> {
  return (await check(await fetch('api/presets'), 'GET /api/presets')).json();
}

// Selected volume of every step and the depth profile of the state's step (POST /api/stats).
// With `allProfiles` the answer holds every step's depth profile (`profiles`), not only the state's step's.
export async function postStats(state: RenderState, level: number | undefined, signal?: AbortSignal,
  allProfiles = false): Promise<SelectionOverTime> {
  const query = [level === undefined ? '' : `level=${level}`, allProfiles ? 'profiles=all' : ''].filter((x) => x).join('&');
  const r = await fetch(`api/stats${query ? `?${query}` : ''}`, {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state), signal,
  });
  return (await check(r, 'POST /api/stats')).json();
}

// The features of the state's selection followed through the series, with the state's feature
// settings (POST /api/features, docs/features.md); `job` names the request for getJobProgress.
export async function postFeatures(state: RenderState, job: string, signal?: AbortSignal): Promise<FeatureSeries> {
  const r = await fetch(`api/features?job=${encodeURIComponent(job)}`, {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state), signal,
  });
  return (await check(r, 'POST /api/features')).json();
}

// Where the request postFeatures named `job` is (GET /api/job-progress).
export async function getJobProgress(job: string, signal?: AbortSignal): Promise<JobProgress> {
  const r = await fetch(`api/job-progress?job=${encodeURIComponent(job)}`, { signal });
  return (await check(r, 'GET /api/job-progress')).json();
}

// The values of the time–depth picture (POST /api/time-depth?format=csv): `raypc stats --profile`'s
// table, with the means of `variable` when given.
export async function postTimeDepthCsv(state: RenderState, variable: string | undefined, signal?: AbortSignal): Promise<string> {
  const q = new URLSearchParams({ format: 'csv' });
  if (variable !== undefined) q.set('var', variable);
  const r = await fetch(`api/time-depth?${q}`, {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state), signal,
  });
  return (await check(r, 'POST /api/time-depth?format=csv')).text();
}

// The time–depth picture of the state's selection (POST /api/time-depth): a PNG drawn by the server
// (`of`: share, selected-mean or shell-mean of `variable`).
export async function postTimeDepth(state: RenderState, of: string, variable: string | undefined, width: number, height: number,
  signal?: AbortSignal): Promise<Blob> {
  const q = new URLSearchParams({ of, width: String(width), height: String(height) });
  if (variable !== undefined) q.set('var', variable);
  const r = await fetch(`api/time-depth?${q}`, {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state), signal,
  });
  return (await check(r, 'POST /api/time-depth')).blob();
}

export type PathlineAttributes = PathlinesHeader & { values: Float32Array }; // lines x columns, row-major

// The line attributes of the pathlines shown at `step` (GET /api/pathlines): u32 LE header length,
// JSON header, float32 LE values.
export async function fetchPathlines(step: number, window: number, signal?: AbortSignal): Promise<PathlineAttributes> {
  const r = await check(await fetch(`api/pathlines?step=${step}&window=${window}`, { signal }), 'GET /api/pathlines');
  const buffer = await r.arrayBuffer();
  if (buffer.byteLength < 4) throw new Error('GET /api/pathlines: answer shorter than its header length');
  const n = new DataView(buffer).getUint32(0, true);
  if (4 + n > buffer.byteLength) throw new Error(`GET /api/pathlines: header of ${n} bytes does not fit in ${buffer.byteLength}`);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, n))) as PathlinesHeader;
  const valueBytes = buffer.byteLength - 4 - n;
  const expected = header.lines * header.columns.length * 4;
  if (valueBytes !== expected) throw new Error(`GET /api/pathlines: ${valueBytes} bytes of values, expected ${expected}`);
  // Copy: the values start at an offset that need not be a multiple of 4.
  const values = new Float32Array(buffer.slice(4 + n));
  return { ...header, values };
}

// The persistence diagram of `step` (GET /api/persistence): the `top` most persistent pairs.
export async function fetchPersistence(step: number, top: number, signal?: AbortSignal): Promise<PersistenceDiagram> {
  return (await check(await fetch(`api/persistence?step=${step}&top=${top}`, { signal }), 'GET /api/persistence')).json();
}

export async function postSlice(view: 'map' | 'section', state: RenderState): Promise<{ header: SliceHeader; png: Blob }> {
  const r = await fetch(`api/slice?view=${view}`, {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state),
  });
  const body = await (await check(r, `POST /api/slice?view=${view}`)).arrayBuffer();
  const n = body.byteLength >= 4 ? new DataView(body).getUint32(0, true) : -1;
  if (n < 0 || 4 + n > body.byteLength) throw new Error(`POST /api/slice: an answer of ${body.byteLength} bytes without its header`);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(body, 4, n))) as SliceHeader;
  return { header, png: new Blob([new Uint8Array(body, 4 + n)], { type: 'image/png' }) };
}

// The power per spherical-harmonic degree of the state's colour variable at its step, on the shell
// nearest the map's depth (POST /api/spectrum; docs/compare.md, as `raypc spectrum` computes it).
export async function postSpectrum(state: RenderState): Promise<Spectrum> {
  const r = await fetch('api/spectrum', {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state),
  });
  return (await check(r, 'POST /api/spectrum')).json();
}

// A pair's two datasets correlated shell by shell, the state's colour variable at its step and the
// second's matched step (POST /api/correlate; docs/compare.md, as `raypc correlate` computes it).
export async function postPairCorrelation(state: RenderState): Promise<PairCorrelation> {
  const r = await fetch('api/correlate', {
    method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(state),
  });
  return (await check(r, 'POST /api/correlate')).json();
}

// The values at a point (GET /api/probe; analysis/probe.h, as `raypc probe`).
export async function fetchProbe(step: number, lat: number, lon: number, depthKm: number, variable: string): Promise<ProbeAnswer> {
  const q = new URLSearchParams({ step: String(step), lat: String(lat), lon: String(lon), depthKm: String(depthKm), var: variable });
  return (await check(await fetch(`api/probe?${q}`), 'GET /api/probe')).json();
}
