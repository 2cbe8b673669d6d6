// The server's orbit camera (src/render/camera.{h,cpp}: OrbitCamera, CameraFrame), mirrored
// exactly so a depth map can be unprojected with the frame's camera and reprojected with the
// current one. Positions are Cartesian km in the contest frame; +z is up; azimuth in the x-y
// plane from +x towards +y, elevation towards +z, degrees. Pixel (0, 0) is the top-left corner.
// An explicit view (state camera.views, CameraView: e.g. a WebXR eye) replaces the orbit's pose and
// frustum: position km, unit quaternion [x, y, z, w] from camera axes (looking along -z, +y up, +x
// right) to the contest frame, frustum tangents [left, right, down, up].
import type { CameraState, StereoState } from './state';
import type { CameraView } from './generated/state_types';

export type { CameraView };
export type Vec3 = [number, number, number];
export type Quaternion = [number, number, number, number]; // [x, y, z, w]

const dot = (a: Vec3, b: Vec3) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a: Vec3, b: Vec3): Vec3 => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const scale = (a: Vec3, s: number): Vec3 => [a[0] * s, a[1] * s, a[2] * s];
const add = (a: Vec3, b: Vec3): Vec3 => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const normalize = (a: Vec3): Vec3 => scale(a, 1 / Math.sqrt(dot(a, a)));
const degToRad = (d: number) => (d * Math.PI) / 180;

// The rotation of unit quaternion q applied to v.
export function rotate(q: Quaternion, v: Vec3): Vec3 {
  const [x, y, z, w] = q;
  return [
    (1 - 2 * (y * y + z * z)) * v[0] + 2 * (x * y - z * w) * v[1] + 2 * (x * z + y * w) * v[2],
    2 * (x * y + z * w) * v[0] + (1 - 2 * (x * x + z * z)) * v[1] + 2 * (y * z - x * w) * v[2],
    2 * (x * z - y * w) * v[0] + 2 * (y * z + x * w) * v[1] + (1 - 2 * (x * x + y * y)) * v[2],
  ];
}

// The Hamilton product a b: the rotation b, then a.
export function multiply(a: Quaternion, b: Quaternion): Quaternion {
  const [ax, ay, az, aw] = a, [bx, by, bz, bw] = b;
  return [aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
    aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz];
}

// The unit quaternion of the rotation whose matrix has the orthonormal columns a, b, c (Shepperd).
export function quaternionOfColumns(a: Vec3, b: Vec3, c: Vec3): Quaternion {
  const [m00, m10, m20] = a, [m01, m11, m21] = b, [m02, m12, m22] = c;
  const trace = m00 + m11 + m22;
  let q: Quaternion;
  if (trace > 0) {
    const s = 2 * Math.sqrt(1 + trace);
    q = [(m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, s / 4];
  } else if (m00 > m11 && m00 > m22) {
    const s = 2 * Math.sqrt(1 + m00 - m11 - m22);
    q = [s / 4, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s];
  } else if (m11 > m22) {
    const s = 2 * Math.sqrt(1 + m11 - m00 - m22);
    q = [(m01 + m10) / s, s / 4, (m12 + m21) / s, (m02 - m20) / s];
  } else {
    const s = 2 * Math.sqrt(1 + m22 - m00 - m11);
    q = [(m02 + m20) / s, (m12 + m21) / s, s / 4, (m10 - m01) / s];
  }
  const n = Math.hypot(...q);
  return q.map((x) => x / n) as Quaternion;
}

// One eye of a stereo pair (OrbitCamera's eyeOffsetKm, convergenceKm, pixelAspect; stereoEye):
// the eye moved along the image's right axis, the image window shifted so that the view axis'
// point at convergenceKm has no parallax (parallel axes, off-axis frustum).
export interface EyeOffset {
  eyeOffsetKm: number;
  convergenceKm: number;
  pixelAspect: number;
}

// The views of a state (StateRenderer's stereoViews and stereoLayout): one eye of the orbit
// camera, or the left and right eye with their sizes; `width` x `height` is the composed image.
export interface StereoLayout {
  mode: string;
  eyes: (EyeOffset & { width: number; height: number })[];
  width: number;
  height: number;
}

export function stereoLayout(stereo: StereoState | undefined, camera: CameraState, width: number, height: number): StereoLayout {
  const mode = stereo?.mode ?? 'off';
  if (!stereo || mode === 'off')
    return { mode: 'off', eyes: [{ eyeOffsetKm: 0, convergenceKm: 0, pixelAspect: 1, width, height }], width, height };
  const half = mode === 'side-by-side-half';
  const eyeWidth = half ? Math.max(1, Math.floor(width / 2)) : width;
  const pixelAspect = half ? width / eyeWidth : 1;
  const convergenceKm = stereo.convergenceKm ?? camera.distanceKm;
  const eyes = [-0.5, 0.5].map((side) => ({ eyeOffsetKm: side * stereo.eyeSeparationKm, convergenceKm, pixelAspect, width: eyeWidth, height }));
  return { mode, eyes, width: mode === 'anaglyph' ? width : 2 * eyeWidth, height };
}

export class CameraFrame {
  readonly eye: Vec3;
  readonly forward: Vec3;
  readonly right: Vec3;
  readonly up: Vec3;
  readonly tanHalfFovY: number;
  readonly aspect: number;
  readonly shiftX: number; // horizontal shift of the image window, tangent units (an off-axis frustum)
  readonly shiftY: number = 0; // vertical shift (an explicit view)

  // The orbit camera (one eye of it with `eye`), or `view` when given (the eye offset does not apply).
  constructor(camera: CameraState, readonly width: number, readonly height: number, eye?: EyeOffset, view?: CameraView) {
    if (view) {
      const q = view.orientation as Quaternion;
      const n = Math.hypot(...q);
      const u = q.map((x) => x / n) as Quaternion;
      this.right = rotate(u, [1, 0, 0]);
      this.up = rotate(u, [0, 1, 0]);
      this.forward = rotate(u, [0, 0, -1]);
      this.eye = [...view.positionKm] as Vec3;
      const [left, right, down, up] = view.frustum;
      this.tanHalfFovY = (up - down) / 2;
      this.aspect = (right - left) / (up - down);
      this.shiftX = (right + left) / 2;
      this.shiftY = (up + down) / 2;
      return;
    }
    // As the server: keep the elevation a hair away from ±90° so +z never becomes the view direction.
    const el = degToRad(Math.min(89.999, Math.max(-89.999, camera.elevationDeg)));
    const az = degToRad(camera.azimuthDeg);
    const offset: Vec3 = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
    this.forward = normalize(scale(offset, -1));
    this.right = normalize(cross(this.forward, [0, 0, 1]));
    this.up = cross(this.right, this.forward);
    const eyeOffsetKm = eye?.eyeOffsetKm ?? 0;
    this.eye = add(add(camera.targetKm, scale(offset, camera.distanceKm)), scale(this.right, eyeOffsetKm));
    this.shiftX = eye && eye.convergenceKm > 0 ? -eyeOffsetKm / eye.convergenceKm : 0;
    this.tanHalfFovY = Math.tan(degToRad(camera.fovYDeg) * 0.5);
    this.aspect = (width * (eye?.pixelAspect ?? 1)) / height;
  }

  // Unit direction through continuous image position (px, py); the centre of pixel i is i + 0.5.
  direction(px: number, py: number): Vec3 {
    const sx = ((2 * px) / this.width - 1) * this.tanHalfFovY * this.aspect + this.shiftX;
    const sy = (1 - (2 * py) / this.height) * this.tanHalfFovY + this.shiftY;
    return normalize(add(add(this.forward, scale(this.right, sx)), scale(this.up, sy)));
  }

  // Image position (px, py) of a world point and its camera-space depth along `forward`
  // (z <= 0: behind the eye).
  project(p: Vec3): { px: number; py: number; z: number } {
    const d: Vec3 = [p[0] - this.eye[0], p[1] - this.eye[1], p[2] - this.eye[2]];
    const z = dot(d, this.forward);
    const sx = (dot(d, this.right) / z - this.shiftX) / (this.tanHalfFovY * this.aspect);
    const sy = (dot(d, this.up) / z - this.shiftY) / this.tanHalfFovY;
    return { px: ((sx + 1) * this.width) / 2, py: ((1 - sy) * this.height) / 2, z };
  }
}

export function camerasEqual(a: CameraState, b: CameraState): boolean {
  return a.azimuthDeg === b.azimuthDeg && a.elevationDeg === b.elevationDeg && a.distanceKm === b.distanceKm &&
    a.fovYDeg === b.fovYDeg && a.targetKm[0] === b.targetKm[0] && a.targetKm[1] === b.targetKm[1] &&
    a.targetKm[2] === b.targetKm[2] && JSON.stringify(a.views) === JSON.stringify(b.views);
}

// The view of an orbit camera's frame (its pose and symmetric or shifted frustum).
export function viewOfFrame(f: CameraFrame): CameraView {
  const tx = f.tanHalfFovY * f.aspect;
  return {
    positionKm: [...f.eye],
    orientation: quaternionOfColumns(f.right, f.up, scale(f.forward, -1)),
    frustum: [f.shiftX - tx, f.shiftX + tx, f.shiftY - f.tanHalfFovY, f.shiftY + f.tanHalfFovY],
  };
}
