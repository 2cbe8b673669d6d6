// HTTP side of docs/protocol.md: dataset info, histograms, the parallel-coordinates sample,
// exact selection volumes and screenshots. Every function throws an Error naming the endpoint
// and the server's message on a non-2xx answer.
import type { RenderState } from './state';

export interface VariableInfo {
  name: string;
  units: string;
  derived: boolean;
  min: number;
  max: number;
  mean: number;
  histogram: number[];
}
export interface CoordinateInfo {
  name: string;
  units: string;
  min: number;
  max: number;
}
export interface StepInfo {
  index: number;
  timeMyr: number;
  source: string;
}
export interface Info {
  protocol: number;
  variables: VariableInfo[];
  coordinates: CoordinateInfo[];
  steps: StepInfo[];
  levels: { level: number; nLat: number; nR: number; nLon: number }[];
  sample: { rows: number; columns: string[]; units: string[] };
  colorMaps: string[];
  defaultState: RenderState;
}
export interface Histogram {
  name: string;
  units: string;
  min: number;
  max: number;
  histogram: number[];
}
export interface Selection {
  fractionOfMantle: number;
  volumeKm3: number;
  step?: number;
}
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

export async function fetchInfo(): Promise<Info> {
  return (await check(await fetch('api/info'), 'GET /api/info')).json();
}

export async function fetchHistogram(step: number, variable: string): Promise<Histogram> {
  const url = `api/histogram?step=${step}&var=${encodeURIComponent(variable)}`;
  return (await check(await fetch(url), 'GET /api/histogram')).json();
}

export async function fetchSample(step: number, columns: string[]): Promise<Sample> {
  const r = await check(await fetch(`api/sample?step=${step}`), 'GET /api/sample');
  const buffer = await r.arrayBuffer();
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
