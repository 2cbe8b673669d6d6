// The one-line description of a preset (shown under the preset buttons): what it colours, what
// its brushes select, and the step it shows, in the units of the axes.
import type { AxisInfo } from './parcoords';
import { fmt } from './selection_panel';
import { rangesByName, type Brush, type RenderState } from './state';
import { displayUnits } from './units';

// A range as a reader says it: an end beyond the axis's data is open ("≤ -25", "≥ 100"), not the
// placeholder a preset writes there (-1e4).
function describeRange(lo: number, hi: number, axis: AxisInfo | undefined): string {
  const openBelow = axis !== undefined && lo <= axis.min, openAbove = axis !== undefined && hi >= axis.max;
  if (openBelow && openAbove) return 'any value';
  if (openBelow) return `≤ ${fmt(hi)}`;
  if (openAbove) return `≥ ${fmt(lo)}`;
  return `${fmt(lo)} … ${fmt(hi)}`;
}

export function describePreset(s: RenderState, axes: AxisInfo[]): string {
  const units = (name: string) => {
    const u = axes.find((a) => a.name === name)?.units ?? '';
    return u ? ` ${displayUnits(u)}` : '';
  };
  const parts = [`step ${s.step}`, `colour ${s.color.variable} (${s.color.points.length ? 'custom colours' : s.color.colorMap})`];
  if (s.brushes.length)
    parts.push(`selects ${[...rangesByName(s.brushes)].map(([name, ranges]) =>
      `${name} ${ranges.map(([lo, hi]) => describeRange(lo, hi, axes.find((a) => a.name === name))).join(' or ')}${units(name)}`).join(' and ')}`);
  else parts.push('no brushes');
  if (s.pathlines?.visible) parts.push(`pathlines of the last ${s.pathlines.window} steps`);
  return parts.join('; ');
}

// Whether two selections are the same brushes (in any order; ends equal to a millionth of their
// size, as a saved and reloaded document or the parallel coordinates may round them).
export function sameBrushes(a: readonly Brush[], b: readonly Brush[]): boolean {
  if (a.length !== b.length) return false;
  const near = (x: number, y: number) => Math.abs(x - y) <= 1e-6 * Math.max(1, Math.abs(x), Math.abs(y));
  const left = [...b];
  return a.every((p) => {
    const i = left.findIndex((q) => q.name === p.name && near(q.min, p.min) && near(q.max, p.max));
    if (i < 0) return false;
    left.splice(i, 1);
    return true;
  });
}
