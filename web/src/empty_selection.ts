// The note under the Selection panel's figure when the brushes select nothing (a preset made for
// another model, a range beyond a variable's values): which brush excluded everything, from the
// facts the server gives with the empty selection (POST /api/selection's `empty`: what each brushed
// axis selects alone and what the others select without it; docs/protocol.md).
import type { Selection } from './api';

const percent = (f: number) => `${(f * 100).toFixed(2)} %`;

const list = (names: string[]) => (names.length < 2 ? names.join('') : `${names.slice(0, -1).join(', ')} and ${names[names.length - 1]}`);

// The note's text for the selection answer `s` (null: none yet), or '' when nothing is to be said.
export function emptySelectionNote(s: Selection | null): string {
  if (!s || !s.empty || !s.empty.length || s.fractionOfMantle > 0) return '';
  const alone = s.empty.filter((e) => e.alone === 0).map((e) => e.name);
  if (alone.length) {
    return `Nothing is selected at step ${s.step}: the brush on ${list(alone)} ${alone.length > 1 ? 'each select' : 'selects'} ` +
      `nothing by ${alone.length > 1 ? 'themselves' : 'itself'} (no value there lies in ${alone.length > 1 ? 'their ranges' : 'its range'}).`;
  }
  const culprits = s.empty.filter((e) => e.withoutIt > 0);
  if (culprits.length) {
    return `Nothing is selected at step ${s.step}: the brush on ${list(culprits.map((e) => e.name))} excludes everything the others select ` +
      `(without it: ${culprits.map((e) => `${percent(e.withoutIt)} of the mantle`).join('; ')}).`;
  }
  return `Nothing is selected at step ${s.step}: each brush selects something alone ` +
    `(${s.empty.map((e) => `${e.name} ${percent(e.alone)}`).join(', ')}), but no point lies in all of them together.`;
}

// Shows the note for `s` in #emptySelection (hidden when there is nothing to say).
export function showEmptySelection(s: Selection | null): void {
  const el = document.getElementById('emptySelection');
  if (!el) return;
  el.textContent = emptySelectionNote(s);
  el.hidden = el.textContent === '';
}
