// Units as the UI writes them, the same everywhere (axis titles, selects, legends, tables): exponents
// as superscripts ("kg/m^3" -> "kg/m³") and CF angle names as symbols ("degrees_north" -> "°N"),
// as the renderer's legends write them (src/render/legend.cpp, displayUnits).
export function displayUnits(units: string): string {
  if (units === 'degrees_north') return '°N';
  if (units === 'degrees_east') return '°E';
  return units.replace(/\^2/g, '²').replace(/\^3/g, '³');
}
