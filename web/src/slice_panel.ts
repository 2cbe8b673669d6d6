// The map of a depth slice and the great-circle section (docs/maps.md; state.map and
// state.section): the server draws both for the state in force (POST /api/slice, the renderer's
// render/slice_view.h, as `raypc map` and `raypc section` draw them) in the bottom panel's "Map &
// section" tab; their controls are the side panel's "Map and section". The pointer reads the point
// under it with d3's projection placed as the server placed it (the same formulas, tested against
// each other) and its values from the server (GET /api/probe); a click on the map sets the
// section's start (A), the next its end (B), and the hint under the map says which comes next.
// Over the map the page draws, with that projection, the section's line and its ends A and B,
// and (unless the state's reference has the server draw them) a labelled graticule and the
// coastlines: crisp at any size, on by default.
import { geoEquirectangular, geoGraticule, geoInterpolate, geoOrthographic, geoPath, geoRotation, type GeoProjection } from 'd3-geo';
import { geoHammer, geoMollweide, geoRobinson } from 'd3-geo-projection';
import { fetchProbe, postSlice, postSpectrum, type SliceHeader } from './api';
import type { MapHeader } from './generated/protocol_types';
import type { RenderState } from './state';
import type { StateStore } from './store';
import { drawSpectrumPlot } from './spectrum_plot';
import { displayUnits } from './units';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

// Every projection the server draws (its names are the protocol's, so a new one is a type error here).
const kProjections: Record<MapHeader['projection'], () => GeoProjection> = {
  equirectangular: geoEquirectangular,
  mollweide: geoMollweide,
  hammer: geoHammer,
  robinson: geoRobinson,
  orthographic: geoOrthographic,
};

export interface SlicePanelHost {
  // The state changed only in its map or section: kept (the URL), and a new frame of the 3D view
  // only while it marks them (map.showInView).
  changed(): void;
  showError(message: string): void;
}

type View = 'map' | 'section';

// What of a state a picture depends on: not the 3D view's camera, stereo, shading, core or axes,
// nor the other picture's settings (a dragged map depth redraws no section). JSON, to compare.
function pictureKey(view: View, state: RenderState): string {
  const { camera: _c, stereo: _s, shading: _sh, core: _co, axes: _a, map, section, ...rest } = state;
  return JSON.stringify(view === 'map'
    ? { ...rest, map: { ...map, showInView: false } }
    : { ...rest, section, greyUnselected: map.greyUnselected, contours: map.contours });
}

// One picture: at most one request in flight; a state that changes meanwhile is drawn next; a
// state that changes nothing the picture shows asks for none.
class SlicePicture {
  header: SliceHeader | null = null;
  private busy = false;
  private dirty = false;
  private url = '';
  private key = ''; // pictureKey of the picture shown or asked for
  // How many pictures have been shown (tests wait for the next one).
  shown = 0;

  constructor(readonly view: View, readonly image: HTMLImageElement, private readonly state: () => RenderState | null,
    private readonly showError: (m: string) => void, private readonly onShown: (h: SliceHeader) => void = () => {}) {}

  request(): void {
    if (this.busy) {
      this.dirty = true;
      return;
    }
    const state = this.state();
    if (!state) return;
    const key = pictureKey(this.view, state);
    if (key === this.key) return;
    this.key = key;
    this.busy = true;
    this.dirty = false;
    postSlice(this.view, state)
      .then(({ header, png }) => {
        if (this.url) URL.revokeObjectURL(this.url);
        this.url = URL.createObjectURL(png);
        this.image.src = this.url;
        this.header = header;
        this.shown++;
        this.onShown(header);
      })
      .catch((e: Error) => {
        this.key = ''; // asked again next time
        this.showError(e.message);
      })
      .finally(() => {
        this.busy = false;
        if (this.dirty) this.request();
      });
  }

  // The point of the picture under a mouse event, in the picture's pixels.
  pixelOf(e: MouseEvent): [number, number] | null {
    if (!this.header || !this.image.clientWidth) return null;
    // The picture is drawn whole at the element's top left (object-fit: contain).
    const r = this.image.getBoundingClientRect();
    const cssPerPixel = Math.min(r.width / this.header.width, r.height / this.header.height);
    return [(e.clientX - r.left) / cssPerPixel, (e.clientY - r.top) / cssPerPixel];
  }
}

export class SlicePanel {
  readonly map: SlicePicture;
  readonly section: SlicePicture;
  private visible = false;
  private nextEnd: 'from' | 'to' = 'from';
  private probeBusy = false;
  private probeNext: (() => void) | null = null;

  constructor(private readonly store: StateStore, private readonly host: SlicePanelHost) {
    const sized = (image: HTMLImageElement) => (): RenderState | null => {
      const box = image.parentElement!.getBoundingClientRect();
      const dpr = window.devicePixelRatio || 1;
      const width = Math.round(box.width * dpr), height = Math.round((box.height - 20) * dpr);
      if (width < 64 || height < 64) return null;
      return { ...this.store.state, image: { width, height } };
    };
    this.map = new SlicePicture('map', $<HTMLImageElement>('mapImage'), sized($<HTMLImageElement>('mapImage')), host.showError,
      () => this.drawMarks());
    this.section = new SlicePicture('section', $<HTMLImageElement>('sectionImage'),
      sized($<HTMLImageElement>('sectionImage')), host.showError, (h) => this.showArc(h));
    this.setUpControls();
    this.setUpPointer();
    new ResizeObserver(() => { this.stateChanged(); this.drawMarks(); }).observe($('slices'));
    $('spectrumDetails').addEventListener('toggle', () => { if (this.visible) this.requestSpectrum(); });
    this.showHint();
    // The coastlines the UI build wrote beside the page (web/build.mjs), as the server draws them.
    fetch('coastlines.json')
      .then((r) => (r.ok ? r.json() : null))
      .then((c: { lines: number[][] } | null) => {
        if (!c) return;
        this.coastlines = { type: 'MultiLineString', coordinates: c.lines.map((l) => l.flatMap((_v, i) => (i % 2 ? [] : [[l[i], l[i + 1]]]))) };
        this.drawMarks();
      })
      .catch(() => {});
  }

  private coastlines: GeoJSON.MultiLineString | null = null;

  // The hint under the map: which end the next click sets.
  private showHint(): void {
    $('mapReadout').textContent = this.nextEnd === 'from'
      ? 'click the map: sets A (the section\u2019s start)'
      : 'click the map: sets B (the section\u2019s end)';
  }

  // The map's projection as the server placed it (the header of its picture), or null.
  private projection(): GeoProjection | null {
    const h = this.map.header;
    if (h?.view !== 'map') return null;
    return kProjections[h.projection]().scale(h.scale).translate(h.centre).rotate([-h.centralMeridianDeg, -h.centralLatitudeDeg]);
  }

  // Draws over the map picture (#mapMarks, in the picture's pixels): the graticule every 30° with
  // its labels and the coastlines (where the state's reference does not have the server draw
  // them), the section's great circle and its ends A and B.
  drawMarks(): void {
    const svg = document.getElementById('mapMarks') as unknown as SVGSVGElement | null;
    const h = this.map.header, p = this.projection(), img = this.map.image;
    if (!svg) return;
    if (h?.view !== 'map' || !p || !img.clientWidth) {
      svg.replaceChildren();
      return;
    }
    const box = img.getBoundingClientRect(), pane = img.parentElement!.getBoundingClientRect();
    const cssPerPixel = Math.min(box.width / h.width, box.height / h.height);
    svg.style.left = `${box.left - pane.left}px`;
    svg.style.top = `${box.top - pane.top}px`;
    svg.style.width = `${h.width * cssPerPixel}px`;
    svg.style.height = `${h.height * cssPerPixel}px`;
    svg.setAttribute('viewBox', `0 0 ${h.width} ${h.height}`);
    const px = 1 / cssPerPixel; // one CSS pixel in the picture's pixels
    const path = geoPath(p);
    const ns = 'http://www.w3.org/2000/svg';
    const el = (tag: string, attrs: Record<string, string | number>, text?: string) => {
      const e = document.createElementNS(ns, tag);
      for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
      if (text !== undefined) e.textContent = text;
      return e;
    };
    const out: Element[] = [];
    const ref = this.store.state.reference;
    if (!ref.graticule.visible) {
      out.push(el('path', { class: 'graticule', d: path(geoGraticule().step([30, 30])()) ?? '', 'stroke-width': px }));
      const cm = h.centralMeridianDeg;
      for (const lat of [-60, -30, 0, 30, 60]) {
        const at = p([cm - 179.999, lat]);
        // Inside the map's edge (on a dark halo): outside it, the map's left margin cut them.
        if (at) out.push(el('text', { class: 'graticuleLabel', x: at[0] + 3 * px, y: at[1] + 4 * px, 'text-anchor': 'start', 'font-size': 12 * px }, `${Math.abs(lat)}°${lat < 0 ? 'S' : lat > 0 ? 'N' : ''}`));
      }
      // Meridian labels along 30°S, every 60°, those too close to the last one drawn left out.
      let lastX = -Infinity;
      for (let k = -2; k <= 2; k++) {
        const lon = ((cm + 60 * k + 540) % 360) - 180;
        const at = p([cm + 60 * k, -30]);
        if (!at || at[0] - lastX < 42 * px) continue;
        lastX = at[0];
        out.push(el('text', { class: 'graticuleLabel', x: at[0], y: at[1] + 12 * px, 'text-anchor': 'middle', 'font-size': 12 * px }, `${Math.abs(Math.round(lon))}°${lon < 0 ? 'W' : lon > 0 ? 'E' : ''}`));
      }
    }
    if (!ref.coastlines.visible && this.coastlines) {
      for (const [cls, w] of [['coastlineHalo', 2.6], ['coastline', 1.2]] as const) out.push(el('path', { class: cls, d: path(this.coastlines) ?? '', 'stroke-width': w * px }));
    }
    // The section: its great circle, A at its start and B at its end.
    const { from, to } = this.store.state.section;
    const line: GeoJSON.LineString = { type: 'LineString', coordinates: [[from.lonDeg, from.latDeg], [to.lonDeg, to.latDeg]] };
    out.push(el('path', { class: 'sectionLineHalo', d: path(line) ?? '', 'stroke-width': 5 * px }));
    out.push(el('path', { class: 'sectionLine', d: path(line) ?? '', 'stroke-width': 2.5 * px }));
    for (const [name, end] of [['A', from], ['B', to]] as const) {
      const at = p([end.lonDeg, end.latDeg]);
      if (!at || !Number.isFinite(at[0])) continue;
      const g = el('g', { class: 'sectionEnd', 'data-end': name });
      g.append(el('circle', { cx: at[0], cy: at[1], r: 5 * px, 'stroke-width': 1.5 * px }),
        el('text', { x: at[0] + 7 * px, y: at[1] - 6 * px, 'font-size': 13 * px, 'stroke-width': 3 * px }, name));
      out.push(g);
    }
    svg.replaceChildren(...out);
  }

  // The tab is shown or hidden (app.ts's bottom tabs).
  setVisible(visible: boolean): void {
    const was = this.visible;
    this.visible = visible;
    $('slices').hidden = !visible;
    // While the tab is shown the 3D view marks the map's depth and the section (state.map.showInView).
    if (was !== visible && this.store.state.map.showInView !== visible) {
      this.store.state.map = { ...this.store.state.map, showInView: visible };
      this.host.changed();
    }
    if (visible) this.stateChanged();
  }

  // The map's pane as wide as the map needs at the pane's height (the projection's aspect, and the
  // legend beside it: render/map_view.cpp lays a wide picture out so), at most 62 % of the panel;
  // the section takes the rest. Equal halves left a 2:1 map a third of its pane's width.
  private layoutPanes(): void {
    const pane = $('mapImage').parentElement!, box = $('slices');
    const total = box.clientWidth, h = box.clientHeight - 20; // less the hint under the picture
    if (total < 100 || h < 50) return;
    const aspect = this.store.state.map.projection === 'orthographic' ? 1 : 2;
    // mapLayoutOf's sizes: the text size f, the map at the picture's height less the title band
    // (2.2 f) and margins (1.5 f), margins of f around it, and the legends' panel (the wider of its
    // bar, clamp(W / 4, 8 f, 20 f), and 14 f) plus f.
    const f = Math.max(12, Math.min(48, Math.floor(h / 36)));
    const fixed = aspect * (h - 3.7 * f) + 4 * f;
    const want = Math.max(fixed + 14 * f, Math.min((fixed * 4) / 3, fixed + 20 * f)) + 2;
    pane.style.flex = `0 0 ${Math.round(Math.min(0.62 * total, Math.max(0.3 * total, want)))}px`;
  }

  // The state in force changed: both pictures and the spectrum follow while they are shown.
  stateChanged(): void {
    if (!this.visible) return;
    this.layoutPanes();
    this.map.request();
    this.section.request();
    this.requestSpectrum();
  }

  // The spectrum of the map's depth (POST /api/spectrum) when its variable, step or depth changed; one
  // request at a time, the latest state asked for next.
  private spectrumKey = '';
  private spectrumBusy = false;
  private requestSpectrum(): void {
    if (!$<HTMLDetailsElement>('spectrumDetails').open) return;
    const s = this.store.state;
    const key = JSON.stringify([s.step, s.color.variable, s.map.depthKm]);
    if (key === this.spectrumKey || this.spectrumBusy) return;
    this.spectrumKey = key;
    this.spectrumBusy = true;
    postSpectrum(s)
      .then((answer) => { $('spectrumNote').textContent = drawSpectrumPlot($<SVGSVGElement & HTMLElement>('spectrumPlot'), answer); })
      .catch((e: Error) => {
        $<SVGSVGElement & HTMLElement>('spectrumPlot').replaceChildren();
        $('spectrumNote').textContent = e.message;
      })
      .finally(() => {
        this.spectrumBusy = false;
        this.requestSpectrum();
      });
  }

  // Puts the state into the controls (after a load, a preset, the URL).
  sync(): void {
    const m = this.store.state.map, s = this.store.state.section;
    $<HTMLInputElement>('mapDepth').value = String(m.depthKm);
    $<HTMLInputElement>('mapDepthValue').value = String(m.depthKm);
    $<HTMLSelectElement>('mapProjection').value = m.projection;
    $<HTMLInputElement>('mapMeridian').value = String(m.centralMeridianDeg);
    $<HTMLInputElement>('mapContours').value = m.contours.join(', ');
    $<HTMLInputElement>('mapFlow').checked = m.flow;
    $<HTMLInputElement>('mapGrey').checked = m.greyUnselected;
    $<HTMLInputElement>('sectionFrom').value = `${s.from.latDeg}, ${s.from.lonDeg}`;
    $<HTMLInputElement>('sectionTo').value = `${s.to.latDeg}, ${s.to.lonDeg}`;
    $<HTMLInputElement>('sectionFlow').checked = s.flow;
    this.updateDepthPicks();
  }

  private setUpControls(): void {
    const info = this.store.info;
    // The slider spans the grid's depths (level 0's radii).
    const coordinate = info.coordinates.find((c) => c.name === 'depth');
    const slider = $<HTMLInputElement>('mapDepth');
    slider.min = String(Math.ceil(coordinate?.min ?? 0));
    slider.max = String(Math.floor(coordinate?.max ?? 2886));
    const setDepth = (depth: number, final: boolean) => {
      const lo = Number(slider.min), hi = Number(slider.max);
      if (!Number.isFinite(depth)) return;
      this.store.state.map = { ...this.store.state.map, depthKm: Math.min(hi, Math.max(lo, depth)) };
      $<HTMLInputElement>('mapDepthValue').value = String(this.store.state.map.depthKm);
      slider.value = String(this.store.state.map.depthKm);
      if (final) this.host.changed();
      this.stateChanged();
    };
    slider.addEventListener('input', () => setDepth(Number(slider.value), false));
    slider.addEventListener('change', () => setDepth(Number(slider.value), true));
    $<HTMLInputElement>('mapDepthValue').addEventListener('change', (e) => setDepth(Number((e.target as HTMLInputElement).value), true));
    $('mapDepthPicks').addEventListener('click', (e) => {
      const depth = (e.target as HTMLElement).dataset.depth;
      if (depth) setDepth(Number(depth), true);
    });
    const change = (f: (s: RenderState) => void) => () => {
      f(this.store.state);
      this.host.changed();
      this.stateChanged();
    };
    $('mapProjection').addEventListener('change', change((s) => { s.map = { ...s.map, projection: $<HTMLSelectElement>('mapProjection').value as RenderState['map']['projection'] }; }));
    $('mapMeridian').addEventListener('change', change((s) => {
      const v = Number($<HTMLInputElement>('mapMeridian').value);
      if (Number.isFinite(v)) s.map = { ...s.map, centralMeridianDeg: Math.max(-180, Math.min(180, v)) };
    }));
    $('mapContours').addEventListener('change', change((s) => {
      const text = $<HTMLInputElement>('mapContours').value.trim();
      const values = text ? text.split(/[,\s]+/).map(Number) : [];
      if (values.some((v) => !Number.isFinite(v)) || values.length > 16) {
        this.host.showError(`contours: '${text}': expected up to 16 numbers separated by commas`);
        return;
      }
      s.map = { ...s.map, contours: values as RenderState['map']['contours'] };
    }));
    $('mapFlow').addEventListener('change', change((s) => { s.map = { ...s.map, flow: $<HTMLInputElement>('mapFlow').checked }; }));
    $('mapGrey').addEventListener('change', change((s) => { s.map = { ...s.map, greyUnselected: $<HTMLInputElement>('mapGrey').checked }; }));
    $('sectionFlow').addEventListener('change', change((s) => { s.section = { ...s.section, flow: $<HTMLInputElement>('sectionFlow').checked }; }));
    for (const end of ['from', 'to'] as const) {
      const input = $<HTMLInputElement>(end === 'from' ? 'sectionFrom' : 'sectionTo');
      input.addEventListener('change', () => {
        const parts = input.value.split(',').map((t) => Number(t.trim()));
        if (parts.length !== 2 || !parts.every(Number.isFinite) || Math.abs(parts[0]) > 90 || Math.abs(parts[1]) > 360) {
          this.host.showError(`section ${end}: '${input.value}': expected LAT, LON in degrees (lat in [-90, 90])`);
          return;
        }
        this.setEnd(end, parts[0], parts[1]);
      });
    }
    for (const id of ['sectionAzimuth', 'sectionLength']) $(id).addEventListener('change', () => this.setEndByAzimuth());
  }

  // The section's azimuth and length as the server measured them (the header of its picture),
  // unless the user is typing one.
  private showArc(h: SliceHeader): void {
    if (h.view !== 'section') return;
    for (const [id, v] of [['sectionAzimuth', h.azimuthDeg], ['sectionLength', h.lengthDeg]] as const) {
      const input = $<HTMLInputElement>(id);
      if (document.activeElement !== input) input.value = String(Math.round(v * 10) / 10);
    }
    $('sectionLengthKm').textContent = `${Math.round(h.lengthKm)} km`;
  }

  // The section's end from its start, an azimuth and a length (degrees): d3-geo's rotations, the
  // point `length` north of (0, 0) turned by the azimuth, then (0, 0) moved to the start.
  private setEndByAzimuth(): void {
    const az = Number($<HTMLInputElement>('sectionAzimuth').value);
    const length = Number($<HTMLInputElement>('sectionLength').value);
    if (!Number.isFinite(az) || !(length >= 0.01 && length <= 179.99)) {
      this.host.showError(`section: azimuth '${$<HTMLInputElement>('sectionAzimuth').value}' and length ` +
        `'${$<HTMLInputElement>('sectionLength').value}': expected degrees, the length in [0.01, 179.99]`);
      return;
    }
    const from = this.store.state.section.from;
    const [lon, lat] = geoRotation([-from.lonDeg, -from.latDeg]).invert(geoRotation([0, 0, -az])([0, length]));
    this.setEnd('to', lat, lon);
  }

  // The reference shells' depths as quick picks beside the slider.
  private updateDepthPicks(): void {
    const picks = $('mapDepthPicks');
    const depths = this.store.state.reference.shells.depthsKm;
    const text = depths.join(',');
    if (picks.dataset.depths === text) return;
    picks.dataset.depths = text;
    picks.replaceChildren(...depths.map((d) => {
      const b = document.createElement('button');
      b.textContent = `${d} km`;
      b.dataset.depth = String(d);
      b.title = `Map at ${d} km depth`;
      return b;
    }));
  }

  private setEnd(end: 'from' | 'to', latDeg: number, lonDeg: number): void {
    const s = this.store.state;
    s.section = { ...s.section, [end]: { latDeg: Math.round(latDeg * 100) / 100, lonDeg: Math.round(lonDeg * 100) / 100 } };
    $<HTMLInputElement>(end === 'from' ? 'sectionFrom' : 'sectionTo').value = `${s.section[end].latDeg}, ${s.section[end].lonDeg}`;
    this.host.changed();
    this.stateChanged();
    this.drawMarks();
  }

  // The map's (lon, lat) under a point of its picture, or null off the sphere: d3's projection
  // with the server's scale and centre (a round trip within half a pixel, d3's inverse being
  // defined beyond the sphere too).
  lonLatOnMap(px: number, py: number): [number, number] | null {
    const h = this.map.header;
    if (h?.view !== 'map') return null;
    const p = kProjections[h.projection]().scale(h.scale).translate(h.centre).rotate([-h.centralMeridianDeg, -h.centralLatitudeDeg]);
    const ll = p.invert?.([px, py]);
    if (!ll || !ll.every(Number.isFinite)) return null;
    const back = p(ll);
    if (!back || Math.hypot(back[0] - px, back[1] - py) > 0.5) return null;
    return [((ll[0] + 540) % 360) - 180, ll[1]];
  }

  // The section's (lon, lat, depth) under a point of its picture, or null outside its plot.
  pointOnSection(px: number, py: number): { lon: number; lat: number; depthKm: number } | null {
    const h = this.section.header;
    if (h?.view !== 'section') return null;
    const { left, right, top, bottom } = h.plot;
    if (px < left || px > right || py < top || py > bottom) return null;
    const [lon, lat] = geoInterpolate([h.from[1], h.from[0]], [h.to[1], h.to[0]])((px - left) / (right - left));
    return { lon, lat, depthKm: ((py - top) / (bottom - top)) * h.depthSpanKm };
  }

  private setUpPointer(): void {
    const variable = () => this.store.state.color.variable || this.store.info.variables[0].name;
    const readout = (id: string, lat: number, lon: number, depthKm: number) => {
      const ask = () => {
        this.probeBusy = true;
        fetchProbe(this.store.state.step, lat, lon, depthKm, variable())
          .then((a) => {
            const v = a.values[variable()];
            const where = `${Math.abs(lat).toFixed(1)}°${lat < 0 ? 'S' : 'N'} ${Math.abs(lon).toFixed(1)}°${lon < 0 ? 'W' : 'E'}, ${depthKm.toFixed(0)} km deep`;
            $(id).textContent = v ? `${where}: ${variable()} ${v.value.toPrecision(4)} ${displayUnits(v.units)}` : where;
          })
          .catch(() => { $(id).textContent = ''; })
          .finally(() => {
            this.probeBusy = false;
            const next = this.probeNext;
            this.probeNext = null;
            next?.();
          });
      };
      if (this.probeBusy) this.probeNext = ask;
      else ask();
    };
    const mapImage = this.map.image, sectionImage = this.section.image;
    mapImage.addEventListener('mousemove', (e) => {
      const p = this.map.pixelOf(e);
      const ll = p && this.lonLatOnMap(p[0], p[1]);
      if (ll) readout('mapReadout', ll[1], ll[0], this.store.state.map.depthKm);
      else this.showHint();
    });
    mapImage.addEventListener('mouseleave', () => {
      // The last readout may still be on its way: the hint comes back once it is in.
      const hint = () => this.showHint();
      if (this.probeBusy) this.probeNext = hint;
      else hint();
    });
    mapImage.addEventListener('click', (e) => {
      const p = this.map.pixelOf(e);
      const ll = p && this.lonLatOnMap(p[0], p[1]);
      if (!ll) return;
      this.nextEnd = this.nextEnd === 'from' ? 'to' : 'from';
      this.setEnd(this.nextEnd === 'to' ? 'from' : 'to', ll[1], ll[0]);
      this.showHint();
    });
    sectionImage.addEventListener('mousemove', (e) => {
      const p = this.section.pixelOf(e);
      const q = p && this.pointOnSection(p[0], p[1]);
      if (q) readout('sectionReadout', q.lat, q.lon, q.depthKm);
    });
  }
}
