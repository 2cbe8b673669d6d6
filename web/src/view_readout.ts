// What the 3D view shows, said on the view itself, where the eye is (not below the side panel's
// controls, nor in a status line of developer figures): the step and time of
// the frame on screen, the selected volume and its share of the mantle at that step, and a badge
// when the frame is coarser than the view (a coarser level of detail, or fewer pixels).
//
// Every figure describes the frame shown, never the state sent ahead of it: during playback the
// step is the frame's, and the selection is that step's. A figure counted on a coarser level's grid
// (an interactive frame's, a playback frame's) is marked "≈"; the exact one (level 0: POST
// /api/selection, or the exact statistics over time) replaces it when known for that step.
import type { StepInfo } from './api';
import type { FrameHeader } from './connection';

// A selection figure and the level of the grid it was counted on (0: exact).
export interface SelectionFigure {
  step: number;
  fractionOfMantle: number;
  volumeKm3: number;
  level: number;
}

export interface ReadoutFacts {
  frame: FrameHeader | null;
  steps: StepInfo[];
  brushed: boolean;
  // The view's image size (state.image): what a frame at full size has per eye.
  imageWidth: number;
  imageHeight: number;
  // The selection figures known (of any step): the frame's step's exact one is shown, else its
  // approximate one.
  figures: (SelectionFigure | null)[];
}

// "1.04 %" / "0.0123 %": two decimals, more for small shares so that they do not read as 0.
function percent(fraction: number): string {
  const p = fraction * 100;
  return p !== 0 && Math.abs(p) < 0.1 ? p.toPrecision(2) : p.toFixed(2);
}

// "9.12e8 km³" as 9.12 × 10⁸ km³.
function km3(v: number): string {
  if (!Number.isFinite(v)) return '';
  if (v === 0) return '0 km³';
  const e = Math.floor(Math.log10(Math.abs(v)));
  const sup = String(e).replace(/./g, (c) => '⁰¹²³⁴⁵⁶⁷⁸⁹⁻'['0123456789-'.indexOf(c)]);
  return `${(v / 10 ** e).toFixed(2)} × 10${sup} km³`;
}

// The text of the readout, and of the coarse-frame badge ('' when the frame is at full quality).
export function readoutText(f: ReadoutFacts): { readout: string; badge: string } {
  const h = f.frame;
  if (!h) return { readout: '', badge: '' };
  const info = f.steps[h.step];
  const time = info ? ` · ${info.timeMyr.toFixed(1)} Myr` : '';
  let readout = `step ${h.step}${time}`;
  if (f.brushed) {
    const mine = f.figures.filter((x): x is SelectionFigure => !!x && x.step === h.step && Number.isFinite(x.fractionOfMantle));
    const best = mine.find((x) => x.level === 0) ?? mine[0];
    readout = best
      ? `${best.level === 0 ? '' : '≈ '}${percent(best.fractionOfMantle)} % of the mantle selected${Number.isFinite(best.volumeKm3) ? ` · ${km3(best.volumeKm3)}` : ''} · ${readout}`
      : `selection at step ${h.step}: counting… · ${readout}`;
  }
  // Per eye for a stereo pair; the frame is coarse when its level is above 0 or its eye is smaller
  // than the view's image.
  const w = h.stereo?.eyeWidth ?? h.width, ht = h.stereo?.eyeHeight ?? h.height;
  const smaller = w < f.imageWidth || ht < f.imageHeight;
  const parts: string[] = [];
  if (h.level > 0) parts.push(`level ${h.level} (1/${8 ** h.level} of the cells)`);
  if (smaller) parts.push(`${w}×${ht} px of ${f.imageWidth}×${f.imageHeight}`);
  const badge = parts.length ? `coarse frame: ${parts.join(', ')}${h.converged ? '' : ' · refining'}` : '';
  return { readout, badge };
}
