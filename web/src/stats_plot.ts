// The selection over time (POST /api/stats) as two small d3 plots: the selected share of the
// mantle against time with the current step marked, and the selected share of each shell against
// depth (depth increasing downwards) at the current step.
import * as d3 from 'd3';
import type { SelectionOverTime } from './api';

// Room below the plot for the tick labels and, under them, the axis' title (12 px text).
const kMargin = { top: 8, right: 14, bottom: 36, left: 50 };
export type PlotMargin = typeof kMargin;

// A small plot's frame: the svg emptied, as wide as the panel holding it (docked in the side panel,
// which grows with the window), a group inside `margin` and the inner size.
export function plotFrame(svg: SVGSVGElement, margin: PlotMargin = kMargin) {
  const parentW = (svg.parentElement?.clientWidth ?? 0) - 4;
  if (parentW > 100) svg.setAttribute('width', String(parentW));
  const w = Number(svg.getAttribute('width')), h = Number(svg.getAttribute('height'));
  const root = d3.select(svg);
  root.selectAll('*').remove();
  const g = root.append('g').attr('transform', `translate(${margin.left},${margin.top})`);
  return { g, iw: w - margin.left - margin.right, ih: h - margin.top - margin.bottom };
}
const frame = (svg: SVGSVGElement) => plotFrame(svg);

export function drawTimePlot(svg: SVGSVGElement, s: SelectionOverTime, currentStep: number): void {
  const { g, iw, ih } = frame(svg);
  const pts = s.steps.map((p) => ({ t: p.timeMyr, v: p.fractionOfMantle * 100, step: p.step }));
  const tExt = d3.extent(pts, (p) => p.t) as [number, number];
  const xs = d3.scaleLinear().domain(tExt[0] === tExt[1] ? [tExt[0] - 1, tExt[1] + 1] : tExt).range([0, iw]);
  const ys = d3.scaleLinear().domain([0, Math.max(1e-3, d3.max(pts, (p) => p.v) ?? 1) * 1.1]).range([ih, 0]).nice();
  const x = (v: number) => xs(v) as number, y = (v: number) => ys(v) as number;
  g.append('g').attr('class', 'axis').attr('transform', `translate(0,${ih})`).call(d3.axisBottom(xs).ticks(5).tickFormat(d3.format('~g')));
  g.append('g').attr('class', 'axis').call(d3.axisLeft(ys).ticks(4).tickFormat(d3.format('~g')));
  g.append('text').attr('x', iw).attr('y', ih + 32).attr('text-anchor', 'end').text('time [Myr]');
  g.append('text').attr('x', 2).attr('y', 2).attr('dominant-baseline', 'hanging').text('% of the mantle');
  g.append('path').datum(pts).attr('fill', 'none').attr('stroke', '#8ab4f8').attr('stroke-width', 1.5)
    .attr('d', d3.line<{ t: number; v: number }>().x((p) => x(p.t)).y((p) => y(p.v)));
  g.selectAll('circle.step').data(pts).enter().append('circle').attr('class', 'step')
    .attr('cx', (p) => x(p.t)).attr('cy', (p) => y(p.v)).attr('r', (p) => (p.step === currentStep ? 4 : 1.8))
    .attr('fill', (p) => (p.step === currentStep ? '#ffcc4d' : '#8ab4f8'))
    .append('title').text((p) => `step ${p.step}: ${p.t.toFixed(1)} Myr, ${p.v.toFixed(3)} %`);
  const cur = pts.find((p) => p.step === currentStep);
  if (cur) g.append('line').attr('class', 'current').attr('x1', x(cur.t)).attr('x2', x(cur.t)).attr('y1', 0).attr('y2', ih)
    .attr('stroke', '#ffcc4d').attr('stroke-dasharray', '3,2');
}

export function drawProfilePlot(svg: SVGSVGElement, s: SelectionOverTime): void {
  const { g, iw, ih } = frame(svg);
  const p = s.profile;
  const pts = p.depthKm.map((d, i) => ({ d, v: p.shellVolumeKm3[i] > 0 ? (100 * p.volumeKm3[i]) / p.shellVolumeKm3[i] : 0 }))
    .sort((a, b) => a.d - b.d);
  const dExt = d3.extent(pts, (q) => q.d) as [number, number];
  const ys = d3.scaleLinear().domain(dExt).range([0, ih]); // depth increases downwards
  const xs = d3.scaleLinear().domain([0, Math.max(1e-3, d3.max(pts, (q) => q.v) ?? 1)]).range([0, iw]).nice();
  const x = (v: number) => xs(v) as number, y = (v: number) => ys(v) as number;
  g.append('g').attr('class', 'axis').attr('transform', `translate(0,${ih})`).call(d3.axisBottom(xs).ticks(4).tickFormat(d3.format('~g')));
  g.append('g').attr('class', 'axis').call(d3.axisLeft(ys).ticks(5).tickFormat(d3.format('~g')));
  g.append('text').attr('x', iw).attr('y', ih + 32).attr('text-anchor', 'end').text('% of the shell selected');
  g.append('text').attr('x', 4).attr('y', ih - 4).text('depth [km]');
  g.append('path').datum(pts).attr('class', 'profile').attr('fill', 'rgba(138,180,248,0.35)').attr('stroke', '#8ab4f8')
    .attr('d', d3.area<{ d: number; v: number }>().y((q) => y(q.d)).x0(0).x1((q) => x(q.v)));
}
