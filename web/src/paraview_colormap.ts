// ParaView colour-map JSON (as ParaView's "Choose preset" dialog imports and exports it): a list of
// presets, each with "Name", "ColorSpace", "RGBPoints" [value, r, g, b, ...] in data values and
// optionally "Points" [value, opacity, midpoint, sharpness, ...] and "UseLogScale".

export interface ParaViewMap {
  name: string;
  range: [number, number];
  colorPoints: [number, number, number, number][]; // u, r, g, b normalised over range (log10 with logScale)
  opacity: [number, number][] | null; // u, opacity
  logScale: boolean;
}

function numbers(x: unknown, what: string): number[] {
  if (!Array.isArray(x) || x.some((v) => typeof v !== 'number' || !Number.isFinite(v)))
    throw new Error(`${what}: expected an array of numbers`);
  return x as number[];
}

// Reads the first preset with RGBPoints. Throws an Error naming what is wrong.
export function parseParaViewMap(text: string): ParaViewMap {
  let doc: unknown;
  try {
    doc = JSON.parse(text);
  } catch (e) {
    throw new Error(`not valid JSON: ${(e as Error).message}`);
  }
  const presets = Array.isArray(doc) ? doc : [doc];
  const p = presets.find((x) => x && typeof x === 'object' && 'RGBPoints' in x) as Record<string, unknown> | undefined;
  if (!p) throw new Error('no preset with "RGBPoints" (expected ParaView colour-map JSON)');
  const rgb = numbers(p.RGBPoints, 'RGBPoints');
  if (rgb.length < 8 || rgb.length % 4) throw new Error(`RGBPoints: ${rgb.length} numbers, expected groups of 4 (value, r, g, b), at least 2`);
  const xs = rgb.filter((_v, i) => i % 4 === 0);
  for (let i = 1; i < xs.length; i++) if (xs[i] < xs[i - 1]) throw new Error(`RGBPoints: value ${xs[i]} after ${xs[i - 1]}; expected ascending values`);
  for (let i = 0; i < rgb.length; i++) if (i % 4 && (rgb[i] < 0 || rgb[i] > 1)) throw new Error(`RGBPoints: colour component ${rgb[i]} outside [0, 1]`);
  const lo = xs[0], hi = xs[xs.length - 1];
  if (!(hi > lo)) throw new Error(`RGBPoints: values from ${lo} to ${hi}; expected a range`);
  const logScale = p.UseLogScale === true && lo > 0;
  const pos = (x: number) => Math.min(1, Math.max(0, logScale ? (Math.log10(x) - Math.log10(lo)) / (Math.log10(hi) - Math.log10(lo)) : (x - lo) / (hi - lo)));
  const colorPoints = xs.map((x, k) => [pos(x), rgb[4 * k + 1], rgb[4 * k + 2], rgb[4 * k + 3]] as [number, number, number, number]);
  let opacity: [number, number][] | null = null;
  if (p.Points !== undefined) {
    const o = numbers(p.Points, 'Points');
    if (o.length < 4 || o.length % 4) throw new Error(`Points: ${o.length} numbers, expected groups of 4 (value, opacity, midpoint, sharpness)`);
    opacity = [];
    for (let k = 0; k < o.length; k += 4) opacity.push([pos(o[k]), Math.min(1, Math.max(0, o[k + 1]))]);
    opacity.sort((a, b) => a[0] - b[0]);
  }
  return { name: typeof p.Name === 'string' ? p.Name : 'imported', range: [lo, hi], colorPoints, opacity, logScale };
}

// One preset: the colours at their values ([value, r, g, b], ascending), the opacity points at theirs.
export function paraViewMapJson(name: string, colors: [number, number, number, number][], valueAt: (u: number) => number,
  opacity: [number, number][], logScale: boolean): string {
  const rgb = colors.flatMap(([v, r, g, b]) => [+v.toPrecision(7), +r.toFixed(5), +g.toFixed(5), +b.toFixed(5)]);
  const points = opacity.flatMap(([u, o]) => [+valueAt(u).toPrecision(7), o, 0.5, 0]);
  return JSON.stringify([{ Name: name, ColorSpace: 'RGB', NanColor: [0.5, 0.5, 0.5], RGBPoints: rgb, Points: points, UseLogScale: logScale }], null, 1) + '\n';
}
