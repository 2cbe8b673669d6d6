// Mouse, touch, wheel and keys on the 3D view move state.camera: drag orbits, right/shift/ctrl-drag
// pans, the wheel and pinch zoom; arrow keys orbit, + and - zoom, 0 (or a double-click) resets the
// view. Moves go out as interactive states; releasing (or the wheel or keys resting for 250 ms)
// sends the final state. The eye stays outside the planet (kOutsideFactor × its radius) unless
// "Fly inside" is ticked: inside, the view is uniform and orbiting shows nothing.
import { CameraFrame, type Vec3 } from './camera';
import type { StateStore } from './store';

const kOrbitDegPerPx = 0.35;
const kOrbitDegPerKey = 5, kZoomPerKey = 1.15;
const kMinDistanceKm = 500, kMaxDistanceKm = 500000;
const kPlanetRadiusKm = 6371, kOutsideFactor = 1.05;

// The smallest eye-target distance along the camera's direction that keeps the eye at least
// `radiusKm` from the centre (the eye is target + offset × distance, |offset| = 1).
export function minDistanceOutside(target: Vec3, offset: Vec3, radiusKm: number): number {
  const b = target[0] * offset[0] + target[1] * offset[1] + target[2] * offset[2];
  const c = target[0] ** 2 + target[1] ** 2 + target[2] ** 2 - radiusKm ** 2;
  const disc = b * b - c;
  return disc < 0 ? 0 : Math.max(0, -b + Math.sqrt(disc));
}

export function setUpCameraInput(canvas: HTMLCanvasElement, store: StateStore, commit: (interactive: boolean) => void): void {
  const pointers = new Map<number, { x: number; y: number }>();
  let pan = false;
  let finalTimer = 0;
  // The desktop drives the orbit: explicit views (a state loaded with camera.views) give way to it.
  const cameraChanged = () => {
    store.state.camera.views = [];
    commit(true);
  };
  const panBy = (dxPx: number, dyPx: number) => {
    const cam = store.state.camera;
    const frame = new CameraFrame(cam, store.state.image.width, store.state.image.height);
    const kmPerPx = (2 * cam.distanceKm * frame.tanHalfFovY) / Math.max(1, canvas.clientHeight);
    const t = cam.targetKm;
    for (let k = 0; k < 3; k++) t[k] = t[k] - frame.right[k] * dxPx * kmPerPx + frame.up[k] * dyPx * kmPerPx;
  };
  const flyInside = () => (document.getElementById('flyInside') as HTMLInputElement | null)?.checked === true;
  const keepOutside = () => {
    if (flyInside()) return;
    const cam = store.state.camera;
    const frame = new CameraFrame(cam, 1, 1);
    const offset: Vec3 = [-frame.forward[0], -frame.forward[1], -frame.forward[2]];
    cam.distanceKm = Math.max(cam.distanceKm, minDistanceOutside(cam.targetKm as Vec3, offset, kOutsideFactor * kPlanetRadiusKm));
  };
  const zoomBy = (factor: number) => {
    const cam = store.state.camera;
    cam.distanceKm = Math.min(kMaxDistanceKm, Math.max(kMinDistanceKm, cam.distanceKm * factor));
    keepOutside();
  };
  const orbitBy = (dAzDeg: number, dElDeg: number) => {
    const cam = store.state.camera;
    cam.azimuthDeg = (((cam.azimuthDeg + dAzDeg) % 360) + 360) % 360;
    cam.elevationDeg = Math.min(89.5, Math.max(-89.5, cam.elevationDeg + dElDeg));
    keepOutside();
  };
  const reset = () => {
    store.state.camera = JSON.parse(JSON.stringify(store.defaults.camera));
    commit(false);
  };
  const settle = () => {
    clearTimeout(finalTimer);
    finalTimer = window.setTimeout(() => commit(false), 250);
  };
  canvas.addEventListener('dblclick', reset);
  canvas.addEventListener('keydown', (e) => {
    const keys: Record<string, () => void> = {
      ArrowLeft: () => orbitBy(kOrbitDegPerKey, 0),
      ArrowRight: () => orbitBy(-kOrbitDegPerKey, 0),
      ArrowUp: () => orbitBy(0, kOrbitDegPerKey),
      ArrowDown: () => orbitBy(0, -kOrbitDegPerKey),
      '+': () => zoomBy(1 / kZoomPerKey),
      '=': () => zoomBy(1 / kZoomPerKey),
      '-': () => zoomBy(kZoomPerKey),
    };
    if (e.key === '0' || e.key === 'Home') {
      e.preventDefault();
      reset();
      return;
    }
    const act = keys[e.key];
    if (!act) return;
    e.preventDefault();
    act();
    cameraChanged();
    settle();
  });
  const spread = () => {
    const p = [...pointers.values()];
    return Math.hypot(p[0].x - p[1].x, p[0].y - p[1].y);
  };
  const centroid = () => {
    const p = [...pointers.values()];
    return { x: p.reduce((s, q) => s + q.x, 0) / p.length, y: p.reduce((s, q) => s + q.y, 0) / p.length };
  };
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    canvas.focus();
    canvas.setPointerCapture(e.pointerId);
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    pan = e.button === 2 || e.button === 1 || e.shiftKey || e.ctrlKey;
  });
  canvas.addEventListener('pointermove', (e) => {
    const prev = pointers.get(e.pointerId);
    if (!prev) return;
    if (pointers.size === 1) {
      const dx = e.clientX - prev.x, dy = e.clientY - prev.y;
      if (pan) {
        panBy(dx, dy);
        keepOutside();
      } else orbitBy(-dx * kOrbitDegPerPx, dy * kOrbitDegPerPx);
      pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    } else if (pointers.size === 2) {
      const s0 = spread(), c0 = centroid();
      pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
      const s1 = spread(), c1 = centroid();
      panBy(c1.x - c0.x, c1.y - c0.y);
      if (s1 > 0 && s0 > 0) zoomBy(s0 / s1);
    } else return;
    cameraChanged();
  });
  const up = (e: PointerEvent) => {
    if (!pointers.delete(e.pointerId)) return;
    if (pointers.size === 0) commit(false);
  };
  canvas.addEventListener('pointerup', up);
  canvas.addEventListener('pointercancel', up);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    zoomBy(Math.exp(e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015)));
    cameraChanged();
    settle();
  }, { passive: false });
}
