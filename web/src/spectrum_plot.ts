// The spherical-harmonic power per degree of the shown variable at the map's depth (POST /api/spectrum,
// docs/compare.md): a small d3 plot in the Map and section panel, degree 1..lmax to the right, the power
// on a log axis (degree 0, the shell's mean squared, is left out as in `raypc spectrum --png`).
import * as d3 from 'd3';
import type { Spectrum } from './api';
import { plotFrame } from './stats_plot';
import { displayUnits } from './units';

export function drawSpectrumPlot(svg: SVGSVGElement, s: Spectrum): string {
  const { g, iw, ih } = plotFrame(svg, { top: 20, right: 12, bottom: 34, left: 54 });
  const pts = s.power.map((p, l) => ({ l, p })).filter((d) => d.l >= 1 && d.p > 0);
  svg.dataset.lmax = String(s.lmax);
  svg.dataset.depthKm = String(s.depthKm);
  svg.dataset.points = String(pts.length);
  if (pts.length === 0) return `no lateral variation of ${s.variable} at ${s.depthKm.toFixed(0)} km`;
  const most = d3.max(pts, (d) => d.p) as number;
  const least = Math.max(d3.min(pts, (d) => d.p) as number, most * 1e-6);
  const xs = d3.scaleLinear().domain([1, Math.max(2, s.lmax)]).range([0, iw]);
  const ys = d3.scaleLog().domain([least, most]).range([ih, 0]).nice();
  const units = displayUnits(s.units || '1');
  g.append('g').attr('class', 'axis').attr('transform', `translate(0,${ih})`).call(d3.axisBottom(xs).ticks(6).tickFormat(d3.format('d')));
  g.append('g').attr('class', 'axis').call(d3.axisLeft(ys).ticks(4, '~e'));
  g.append('text').attr('x', iw).attr('y', ih + 31).attr('text-anchor', 'end').text('degree l');
  g.append('text').attr('x', -50).attr('y', -18).attr('dominant-baseline', 'hanging').text(`power [${/[/ ]/.test(units) ? `(${units})` : units}²]`);
  const shown = pts.filter((d) => d.p >= least);
  g.append('path').datum(shown).attr('fill', 'none').attr('stroke', '#8ab4f8').attr('stroke-width', 1.5)
    .attr('d', d3.line<{ l: number; p: number }>().x((d) => xs(d.l) as number).y((d) => ys(d.p) as number));
  g.selectAll('circle').data(shown).enter().append('circle').attr('r', 2).attr('fill', '#8ab4f8')
    .attr('cx', (d) => xs(d.l) as number).attr('cy', (d) => ys(d.p) as number)
    .append('title').text((d) => `degree ${d.l}: ${d.p.toPrecision(4)} ${units}²`);
  return `${s.variable} at ${s.depthKm.toFixed(0)} km (the grid's shell nearest the map's depth), step ${s.step}; ` +
    `4π-normalised, ${s.quadrature}`;
}
