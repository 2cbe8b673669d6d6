// The colour maps of the renderer, from the one table both read (src/state/color_maps.json,
// bundled here and compiled into raypc): stops [u, r, g, b] interpolated linearly in RGB, as
// src/state/color_maps.cpp does. Custom maps are the state's colour control points in the same form.
import table from '../../src/state/color_maps.json';

export type ColorStop = [number, number, number, number]; // u, r, g, b, each in [0, 1]

interface MapEntry {
  name: string;
  kind: string;
  centred: boolean;
  source: string;
  stops: number[][];
}

const maps = new Map<string, MapEntry>((table.maps as MapEntry[]).map((m) => [m.name, m]));

export const colorMapNames: string[] = (table.maps as MapEntry[]).map((m) => m.name);

// Maps whose default range is symmetric around 0 (the renderer's isCentredOnZero).
export const centredMaps = new Set((table.maps as MapEntry[]).filter((m) => m.centred).map((m) => m.name));

// Sequential and diverging maps, for the defaults of a variable.
export function mapKind(name: string): string {
  return maps.get(name)?.kind ?? 'sequential';
}

export function mapSource(name: string): string {
  return maps.get(name)?.source ?? '';
}

export function mapStops(name: string): ColorStop[] {
  return ((maps.get(name) ?? maps.get('viridis')!).stops as ColorStop[]).map((s) => [...s] as ColorStop);
}

// The colour at u of piecewise-linear stops (clamped; NaN counts as 0).
export function sampleStops(stops: ColorStop[], u: number): [number, number, number] {
  u = Math.min(1, Math.max(0, Number.isFinite(u) ? u : 0));
  if (stops.length === 1) return [stops[0][1], stops[0][2], stops[0][3]];
  let i = 1;
  while (i + 1 < stops.length && stops[i][0] < u) i++;
  const a = stops[i - 1], b = stops[i];
  const w = b[0] > a[0] ? (u - a[0]) / (b[0] - a[0]) : 0;
  return [a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]), a[3] + w * (b[3] - a[3])];
}

export function sampleColorMap(name: string, u: number): [number, number, number] {
  return sampleStops((maps.get(name) ?? maps.get('viridis')!).stops as ColorStop[], u);
}
