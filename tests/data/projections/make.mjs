// Writes d3-projections.json: what d3-geo and d3-geo-projection (the UI's projections) give for a
// set of points, so that the C++ map projections (src/render/map_projection.h) are tested against
// d3's values rather than against themselves. Run once, from the repository root, after the UI's
// npm packages are installed (scripts/build-web.sh):
//   node tests/data/projections/make.mjs
// Raw coordinates: scale 1, no translation, y up (d3's screen y is flipped back), radians in and out.
import { writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const web = join(here, '../../../web/node_modules/');
const geo = await import(join(web, 'd3-geo/src/index.js'));
const geoProjection = await import(join(web, 'd3-geo-projection/src/index.js'));

const makers = {
  equirectangular: geo.geoEquirectangular,
  mollweide: geoProjection.geoMollweide,
  hammer: geoProjection.geoHammer,
  robinson: geoProjection.geoRobinson,
  orthographic: geo.geoOrthographic,
};
// Longitudes and latitudes in degrees: a grid with the poles, the seam and odd values.
const lons = [-180, -179.5, -150, -97.3, -45, -1, 0, 0.25, 33.3, 90, 135, 179.5, 180];
const lats = [-90, -89.9, -75, -60.2, -30, -2.5, 0, 4, 37.7, 60, 66.6, 85, 89.9, 90];
const cases = [];
for (const [name, make] of Object.entries(makers)) {
  const centres = name === 'orthographic' ? [[0, 0], [150, 0], [-30, 40], [10, -90]] : [[0, 0], [150, 0], [-30, 0]];
  for (const [lon0, lat0] of centres) {
    const p = make().scale(1).translate([0, 0]).rotate([-lon0, -lat0]);
    const forward = [];
    for (const lon of lons)
      for (const lat of lats) {
        // The orthographic projection shows one hemisphere: points behind it are clipped by d3's
        // stream, not by the raw formula; only the visible ones are kept (angular distance < 89°).
        if (name === 'orthographic' && geo.geoDistance([lon, lat], [lon0, lat0]) > (89 * Math.PI) / 180) continue;
        const [x, y] = p([lon, lat]);
        forward.push([lon, lat, x, -y]);
      }
    // Inversion of the images of interior points (the seam and the poles are many-to-one).
    const inverse = [];
    for (const [lon, lat, x, y] of forward) {
      if (Math.abs(lat) > 89 || Math.abs(((lon - lon0 + 540) % 360) - 180) > 179) continue;
      const back = p.invert([x, -y]);
      inverse.push([x, y, back[0], back[1]]);
    }
    cases.push({ projection: name, centralMeridianDeg: lon0, centralLatitudeDeg: lat0, forward, inverse });
  }
}
const out = {
  source: 'd3-geo ' + (await import(join(web, 'd3-geo/package.json'), { with: { type: 'json' } })).default.version +
    ', d3-geo-projection ' + (await import(join(web, 'd3-geo-projection/package.json'), { with: { type: 'json' } })).default.version +
    ' (tests/data/projections/make.mjs); forward: [lon°, lat°, x, y], inverse: [x, y, lon°, lat°]; scale 1, y up',
  cases,
};
// 12 significant digits: far below the tests' tolerance, a third of the file.
writeFileSync(join(here, 'd3-projections.json'), JSON.stringify(out, (_k, v) => (typeof v === 'number' ? Number(v.toPrecision(12)) : v)) + '\n');
console.log(`wrote ${cases.length} cases`);
