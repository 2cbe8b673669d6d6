// Mouse, touch and wheel on the 3D view move state.camera: drag orbits, right/shift/ctrl-drag pans,
// the wheel and pinch zoom. Moves go out as interactive states; releasing (or the wheel resting for
// 250 ms) sends the final state.
import { CameraFrame } from './camera';
import type { StateStore } from './store';

const kOrbitDegPerPx = 0.35;
const kMinDistanceKm = 500, kMaxDistanceKm = 500000;

export function setUpCameraInput(canvas: HTMLCanvasElement, store: StateStore, commit: (interactive: boolean) => void): void {
  const pointers = new Map<number, { x: number; y: number }>();
  let pan = false;
  let finalTimer = 0;
  const cameraChanged = () => commit(true);
  const panBy = (dxPx: number, dyPx: number) => {
    const cam = store.state.camera;
    const frame = new CameraFrame(cam, store.state.image.width, store.state.image.height);
    const kmPerPx = (2 * cam.distanceKm * frame.tanHalfFovY) / Math.max(1, canvas.clientHeight);
    const t = cam.targetKm;
    for (let k = 0; k < 3; k++) t[k] = t[k] - frame.right[k] * dxPx * kmPerPx + frame.up[k] * dyPx * kmPerPx;
  };
  const zoomBy = (factor: number) => {
    const cam = store.state.camera;
    cam.distanceKm = Math.min(kMaxDistanceKm, Math.max(kMinDistanceKm, cam.distanceKm * factor));
  };
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
      if (pan) panBy(dx, dy);
      else {
        const cam = store.state.camera;
        cam.azimuthDeg = (((cam.azimuthDeg - dx * kOrbitDegPerPx) % 360) + 360) % 360;
        cam.elevationDeg = Math.min(89.5, Math.max(-89.5, cam.elevationDeg + dy * kOrbitDegPerPx));
      }
      pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    } else if (pointers.size === 2) {
      const s0 = spread(), c0 = centroid();
      pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
      const s1 = spread(), c1 = centroid();
      if (s1 > 0 && s0 > 0) zoomBy(s0 / s1);
      panBy(c1.x - c0.x, c1.y - c0.y);
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
    clearTimeout(finalTimer);
    finalTimer = window.setTimeout(() => commit(false), 250);
  }, { passive: false });
}
