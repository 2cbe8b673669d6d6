// A pair's correlation per depth (POST /api/correlate; docs/compare.md, "Correlation"): the shown
// variable of the two datasets, shell by shell on the first's grid, as `raypc correlate --png` plots
// it — depth down, r from −1 to 1, 410 and 660 km marked; the RMS ratio in each point's tooltip. The
// Selection section's "Compare A and B" plot while two datasets are served side by side.
import * as d3 from 'd3';
import type { PairCorrelation } from './api';
import { plotFrame } from './stats_plot';

export function drawPairCorrelation(svg: SVGSVGElement, c: PairCorrelation): string {
  const { g, iw, ih } = plotFrame(svg, { top: 22, right: 12, bottom: 32, left: 48 });
  const rows = c.shells.filter((r) => r.correlation !== null && Number.isFinite(r.correlation));
  svg.dataset.points = String(rows.length);
  if (!rows.length) return `no shell with data in both for ${c.variable}`;
  const maxDepth = d3.max(c.shells, (r) => r.depthKm) ?? 2891;
  const xScale = d3.scaleLinear().domain([-1, 1]).range([0, iw]);
  const xs = (v: number) => xScale(v) as number;
  const yScale = d3.scaleLinear().domain([0, maxDepth]).range([0, ih]);
  const ys = (v: number) => yScale(v) as number;
  g.append('g').attr('class', 'axis').attr('transform', `translate(0,${ih})`).call(d3.axisBottom(xScale).ticks(5));
  g.append('g').attr('class', 'axis').call(d3.axisLeft(yScale).ticks(5));
  g.append('text').attr('x', iw).attr('y', ih + 28).attr('text-anchor', 'end').text('correlation r');
  g.append('text').attr('x', -44).attr('y', -20).attr('dominant-baseline', 'hanging').text('depth [km]');
  for (const d of [410, 660]) {
    if (d > maxDepth) continue;
    g.append('line').attr('x1', 0).attr('x2', iw).attr('y1', ys(d)).attr('y2', ys(d)).attr('stroke', '#9aa4b2').attr('stroke-dasharray', '3,3');
    g.append('text').attr('x', iw - 2).attr('y', ys(d) - 2).attr('text-anchor', 'end').attr('font-size', 12).attr('fill', '#c9d1dc').text(`${d} km`);
  }
  g.append('line').attr('x1', xs(0)).attr('x2', xs(0)).attr('y1', 0).attr('y2', ih).attr('stroke', '#5c6573');
  const pts = rows.map((r) => ({ d: r.depthKm, r: r.correlation as number, ratio: r.rmsRatio }));
  g.append('path').datum(pts).attr('fill', 'none').attr('stroke', '#8ab4f8').attr('stroke-width', 1.5)
    .attr('d', d3.line<{ d: number; r: number }>().x((p) => xs(p.r)).y((p) => ys(p.d)));
  g.selectAll('circle').data(pts).enter().append('circle').attr('r', 2).attr('fill', '#8ab4f8')
    .attr('cx', (p) => xs(p.r)).attr('cy', (p) => ys(p.d))
    .append('title').text((p) => `${p.d.toFixed(0)} km: r = ${p.r.toFixed(3)}, RMS A / B = ${p.ratio === null ? '—' : (p.ratio as number).toPrecision(3)}`);
  const mean = d3.mean(pts, (p) => p.r) as number;
  return `${c.variable}: A step ${c.steps[0]} against B step ${c.steps[1]}, on A's grid; mean r over depth ${mean.toFixed(2)}` +
    (c.lmax !== null ? `, both to degree ${c.lmax}` : '');
}
