// How a variable of the dataset is made, in words, from the facts GET /api/info gives (derived,
// source, computed; docs/protocol.md): stored in the input files, derived at preprocessing, or
// computed when read as a shell anomaly. The Variable menu's and the axes' tooltips say it, so that
// a stored variable and a derived one of a similar name (ASPECT's nonadiabatic_temperature and the
// temperature anomaly) are told apart.
import type { VariableInfo } from './api';

export function variableOrigin(v: Pick<VariableInfo, 'derived' | 'source' | 'computed'>): string {
  if (v.computed) {
    return v.computed.kind === 'anomaly %'
      ? `computed when read: ${v.computed.from}'s difference from its mean over each shell (radius), in % of that mean`
      : `computed when read: ${v.computed.from} minus its mean over each shell (radius)`;
  }
  if (v.derived) return `derived at preprocessing from ${v.source ? v.source : 'other variables'} (not in the input files)`;
  return `stored: read from the input files${v.source ? ` (as '${v.source}')` : ''}`;
}
