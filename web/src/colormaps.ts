// The server's colour maps (src/render/color_map.cpp), for the transfer-function editor's colour bar.
type Stop = [number, number, number, number]; // u, r, g, b

const maps: Record<string, Stop[]> = {
  viridis: [
    [0, 0.267, 0.005, 0.329], [0.125, 0.283, 0.141, 0.458], [0.25, 0.254, 0.265, 0.53], [0.375, 0.207, 0.372, 0.553],
    [0.5, 0.164, 0.471, 0.558], [0.625, 0.128, 0.567, 0.551], [0.75, 0.135, 0.659, 0.518], [0.875, 0.267, 0.749, 0.441],
    [0.9375, 0.478, 0.821, 0.318], [1, 0.993, 0.906, 0.144]],
  inferno: [
    [0, 0.001, 0, 0.014], [0.125, 0.087, 0.045, 0.225], [0.25, 0.258, 0.039, 0.406], [0.375, 0.416, 0.09, 0.433],
    [0.5, 0.578, 0.148, 0.404], [0.625, 0.736, 0.216, 0.33], [0.75, 0.865, 0.317, 0.226], [0.875, 0.955, 0.469, 0.1],
    [0.9375, 0.976, 0.68, 0.15], [1, 0.988, 0.998, 0.645]],
  'cool-to-warm': [
    [0, 0.23, 0.299, 0.754], [0.125, 0.384, 0.51, 0.918], [0.25, 0.552, 0.69, 0.996], [0.375, 0.717, 0.795, 0.95],
    [0.5, 0.865, 0.865, 0.865], [0.625, 0.957, 0.752, 0.651], [0.75, 0.958, 0.603, 0.482], [0.875, 0.866, 0.394, 0.315],
    [1, 0.706, 0.016, 0.15]],
  'blue-white-red': [
    [0, 0.02, 0.188, 0.38], [0.167, 0.129, 0.4, 0.675], [0.333, 0.573, 0.773, 0.871], [0.5, 0.969, 0.969, 0.969],
    [0.667, 0.957, 0.647, 0.51], [0.833, 0.698, 0.094, 0.169], [1, 0.404, 0, 0.122]],
  grayscale: [[0, 0, 0, 0], [1, 1, 1, 1]],
};

// Maps whose default range is symmetric around 0 (the server's isCentredOnZero).
export const centredMaps = new Set(['blue-white-red']);

export function sampleColorMap(name: string, u: number): [number, number, number] {
  const stops = maps[name] ?? maps.viridis;
  u = Math.min(1, Math.max(0, Number.isFinite(u) ? u : 0));
  let i = 1;
  while (i + 1 < stops.length && stops[i][0] < u) i++;
  const a = stops[i - 1], b = stops[i];
  const w = (u - a[0]) / (b[0] - a[0]);
  return [a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]), a[3] + w * (b[3] - a[3])];
}
