// Units as the UI writes them, the same everywhere (axis titles, selects, legends, tables) and as
// the renderer's legends write them: both follow src/render/display_units.json (CF angle names as
// symbols, "degrees_north" -> "°N"; exponents as superscripts, "kg/m^3" -> "kg/m³").
import table from '../../src/render/display_units.json';

const symbols = new Map<string, string>(Object.entries(table.symbols));
const superscripts: Record<string, string> = table.superscripts;
const exponent = new RegExp(`\\^([${Object.keys(superscripts).join('')}])`, 'g');

export function displayUnits(units: string): string {
  return symbols.get(units) ?? units.replace(exponent, (_, digit: string) => superscripts[digit]);
}
