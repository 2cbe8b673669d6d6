// The names of the variables raypc derives and of the columns of the tables it writes, from
// src/grid/names.json: the one table the C++ code's names are generated from and Python reads, so
// that the UI's titles, messages and CSV headers name what the server and the command line write.
import table from '../../src/grid/names.json';

interface Named { key: string; name: string }

// A lookup by the table's keys that fails when the page loads if a key is not in the table.
function byKey(records: readonly Named[], what: string): (key: string) => string {
  const names = new Map(records.map((r) => [r.key, r.name]));
  return (key) => {
    const name = names.get(key);
    if (name === undefined) throw new Error(`${what} '${key}' is not in src/grid/names.json`);
    return name;
  };
}

// A derived variable's name: derivedVariable('radialVelocity') is 'radial velocity'.
export const derivedVariable = byKey(table.derivedVariables, 'derived variable');
// A stored pathline attribute's name: pathlineAttribute('seedKind') is 'seed kind'.
export const pathlineAttribute = byKey(table.columns.pathlineAttributes, 'pathline attribute');
// A pathline's attributes per dataset variable are these prefixes followed by the variable's name.
export const pathlineVariablePrefixes: readonly string[] = table.columns.pathlineVariablePrefixes;
// Every fixed pathline attribute (before the per-variable ones).
export const pathlineAttributeNames: ReadonlySet<string> = new Set(table.columns.pathlineAttributes.map((c) => c.name));
// The columns of `raypc stats -o` (the selected volume over time).
export const selectionOverTimeColumns: readonly string[] = table.columns.selectionOverTime.map((c) => c.name);

// The rule of the shell anomalies every stored variable X gives (computed when read): 'X anomaly'
// in X's units and, where its shell means are positive, 'X anomaly %'.
export const shellAnomaly: { suffix: string; percentSuffix: string; percentUnits: string } = table.shellAnomaly;
// The temperatures a selection can be cold or hot in (features' default stall measure): the
// derived temperature anomaly and the stored temperatures it is derived from ('from').
export const temperatureAnomalyName: string = derivedVariable('temperatureAnomaly');
export const temperatureSources: readonly string[] =
  table.derivedVariables.find((v) => v.key === 'temperatureAnomaly')?.from ?? [];
