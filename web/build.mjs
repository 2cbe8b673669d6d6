// Bundles the UI into web/dist: dist/app.js (esbuild, ES2020, minified, with a source map),
// dist/app.css (our styles followed by parcoord-es's), dist/index.html.
import { build } from 'esbuild';
import { mkdirSync, readFileSync, writeFileSync, copyFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const dist = join(here, 'dist');
mkdirSync(dist, { recursive: true });

await build({
  entryPoints: [join(here, 'src/main.ts')],
  bundle: true,
  format: 'esm',
  target: ['es2020'],
  minify: true,
  sourcemap: true,
  outfile: join(dist, 'app.js'),
  logLevel: 'warning',
  // parcoord-es: use its ES module build (package.json "module"), which imports d3 v1/v2 modules
  // that npm deduplicates with d3@5's; one d3-selection instance keeps d3.event working.
  mainFields: ['module', 'main'],
});

const css = readFileSync(join(here, 'src/style.css'), 'utf8') + '\n' +
  readFileSync(join(here, 'node_modules/parcoord-es/dist/parcoords.css'), 'utf8');
writeFileSync(join(dist, 'app.css'), css);
copyFileSync(join(here, 'src/index.html'), join(dist, 'index.html'));
