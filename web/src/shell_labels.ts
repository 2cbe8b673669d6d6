// The reference shells' depths ("410 km", "660 km") written by the page over the 3D view, where the
// server says each goes on its ring (the frame header's shellLabels, render::shellLabels), and the
// surface's outline (surfaceOutline, render::sphereOutline): crisp text and lines at the page's
// size whatever the frame's size or level, instead of pixels inside a coarse frame. Shown over a
// frame drawn as rendered; hidden while the frame is re-projected to a moving camera (their places
// are the frame's camera's) and for stereo frames (which carry their own labels).
import type { FrameHeader } from './connection';
import type { DrawKind } from './view';

export function placeShellLabels(box: HTMLElement, header: FrameHeader | null, kind: DrawKind,
  rect: { x: number; y: number; width: number; height: number } | null): void {
  const labels = header?.shellLabels ?? [];
  const outline = header?.surfaceOutline ?? [];
  const show = kind === 'exact' && rect !== null && (labels.length > 0 || outline.length > 0);
  box.hidden = !show;
  if (!show || !rect) return;
  const svgNs = 'http://www.w3.org/2000/svg';
  let svg = box.querySelector('svg');
  if (!svg) {
    svg = document.createElementNS(svgNs, 'svg');
    svg.append(document.createElementNS(svgNs, 'polygon'));
    box.prepend(svg);
  }
  svg.querySelector('polygon')!.setAttribute('points',
    outline.map(([x, y]) => `${(rect.x + x * rect.width).toFixed(1)},${(rect.y + y * rect.height).toFixed(1)}`).join(' '));
  const spans = [...box.querySelectorAll<HTMLElement>('.shellLabel')];
  while (spans.length < labels.length) {
    const span = document.createElement('span');
    span.className = 'shellLabel';
    box.appendChild(span);
    spans.push(span);
  }
  spans.forEach((span, i) => {
    const l = labels[i];
    span.hidden = !l;
    if (!l) return;
    span.textContent = l.label;
    const [r, g, b] = l.color.map((c) => Math.round(255 * Math.min(1, Math.max(0, c))));
    span.style.color = `rgb(${r}, ${g}, ${b})`;
    span.style.left = `${rect.x + l.x * rect.width}px`;
    span.style.top = `${rect.y + l.y * rect.height}px`;
  });
}
