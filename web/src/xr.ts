// WebXR immersive-vr (docs/rendering.md, "Stereo", WebXR): head-tracked stereo on a headset.
//
// The XR reference space ('local': its origin where the head was when the session started) is
// mapped onto the planet rigidly: its origin at the eye of the camera the desktop view had when VR
// was entered, its axes on that camera's (+x right, +y up, -z forward), kKmPerMetre km to a metre.
// Each eye's pose and projection become a CameraView (state camera.views: position km, orientation,
// frustum tangents); one state per request holds both eyes as a side-by-side pair, so that the
// server renders them together and the newest-state-wins rule of the protocol never drops one eye
// for the other. At every XR animation frame each eye is drawn into its XRWebGLLayer viewport from
// the last frame, re-projected with its depth map to the eye's current pose (View3D.drawViews, the
// desktop's warping), so the head is answered at the display's rate even while frames lag.
import { CameraFrame, multiply, quaternionOfColumns, rotate, type CameraView, type Quaternion, type Vec3 } from './camera';
import type { RenderLink } from './render_link';
import type { RenderState } from './state';
import type { StateStore } from './store';
import type { Viewport } from './view';

// 1 m in the headset is 10 000 km: the planet (12 742 km across) is a 1.27 m globe, 2.2 m in front
// at the default distance, and the eyes (about 63 mm apart) are about 630 km apart, as the desktop's
// default stereo separation (600 km).
export const kKmPerMetre = 10000;
// Each eye's image is at most this many pixels on its longer side (the server's interactive budget
// and level of detail then set the pace); the eye's viewport stretches it.
const kEyeMaxSide = 512;
// A moving head sends at most one state per this many ms while the server has not answered.
const kResendMs = 120;

// The parts of the WebXR API used here (TypeScript's DOM library has no WebXR types).
interface XRPoint { x: number; y: number; z: number; w?: number }
interface XRViewLike { eye: string; transform: { position: XRPoint; orientation: XRPoint & { w: number } }; projectionMatrix: ArrayLike<number> }
interface XRFrameLike { getViewerPose(space: unknown): { views: readonly XRViewLike[] } | null | undefined }
interface XRLayerLike { framebuffer: WebGLFramebuffer | null; getViewport(view: XRViewLike): Viewport | null | undefined }
interface XRSessionLike {
  requestReferenceSpace(type: string): Promise<unknown>;
  requestAnimationFrame(callback: (time: number, frame: XRFrameLike) => void): number;
  updateRenderState(state: { baseLayer: XRLayerLike }): unknown;
  end(): Promise<void>;
  addEventListener(type: 'end', listener: () => void): void;
}
interface XRSystemLike {
  isSessionSupported(mode: string): Promise<boolean>;
  requestSession(mode: string, options?: { requiredFeatures?: string[] }): Promise<XRSessionLike>;
}
type XRLayerConstructor = new (session: XRSessionLike, gl: WebGL2RenderingContext) => XRLayerLike;

export const kNotAvailable = 'WebXR immersive VR is not available in this browser';

// The signed tangents [left, right, down, up] of a WebGL projection matrix (column-major): for
// x' = P0 x + P8 z, the image's edges x'/w = ±1 with w = -z lie at x/(-z) = (P8 ± 1) / P0.
export function frustumOfProjection(p: ArrayLike<number>): [number, number, number, number] {
  return [(p[8] - 1) / p[0], (p[8] + 1) / p[0], (p[9] - 1) / p[5], (p[9] + 1) / p[5]];
}

// The planet's frame of the XR reference space: the origin and the rotation of its axes.
export interface XrMapping {
  originKm: Vec3;
  rotation: Quaternion;
}

export function mappingOfCamera(frame: CameraFrame): XrMapping {
  return { originKm: [...frame.eye], rotation: quaternionOfColumns(frame.right, frame.up, frame.forward.map((x) => -x) as Vec3) };
}

// An XR view's pose and projection as a camera view in the planet's frame.
export function viewOnPlanet(m: XrMapping, view: XRViewLike): CameraView {
  const { position: p, orientation: o } = view.transform;
  const offset = rotate(m.rotation, [p.x * kKmPerMetre, p.y * kKmPerMetre, p.z * kKmPerMetre]);
  const q = multiply(m.rotation, [o.x, o.y, o.z, o.w]);
  const n = Math.hypot(...q);
  return {
    positionKm: [m.originKm[0] + offset[0], m.originKm[1] + offset[1], m.originKm[2] + offset[2]],
    orientation: q.map((x) => x / n) as Quaternion,
    frustum: frustumOfProjection(view.projectionMatrix),
  };
}

export class XrSession {
  private session: XRSessionLike | null = null;
  private layer: XRLayerLike | null = null;
  private space: unknown = null;
  private mapping: XrMapping | null = null;
  private views: CameraView[] = [];
  private eyeSize = { width: 1, height: 1 };
  private sentKey = '';
  private stillSent = false;
  private lastSend = 0;
  // Animation frames drawn in the session (the browser tests read it).
  framesDrawn = 0;

  constructor(private readonly link: RenderLink, private readonly store: StateStore,
    private readonly onChange: (active: boolean) => void, private readonly onError: (message: string) => void) {}

  get active(): boolean {
    return this.session !== null;
  }

  async enter(xr: XRSystemLike): Promise<void> {
    if (this.session) return;
    const Layer = (window as unknown as { XRWebGLLayer?: XRLayerConstructor }).XRWebGLLayer;
    if (!Layer) throw new Error('WebXR: this browser has no XRWebGLLayer');
    const session = await xr.requestSession('immersive-vr', { requiredFeatures: ['local'] });
    try {
      const gl = this.link.view.context;
      const compatible = (gl as WebGL2RenderingContext & { makeXRCompatible?: () => Promise<void> }).makeXRCompatible;
      if (compatible) await compatible.call(gl);
      this.layer = new Layer(session, gl);
      await session.updateRenderState({ baseLayer: this.layer });
      this.space = await session.requestReferenceSpace('local');
    } catch (e) {
      await session.end().catch(() => {});
      throw e;
    }
    const s = this.store.state;
    this.mapping = mappingOfCamera(new CameraFrame(s.camera, s.image.width, s.image.height, undefined, s.stereo.mode === 'off' ? s.camera.views?.[0] : undefined));
    this.session = session;
    this.views = [];
    this.sentKey = '';
    this.stillSent = false;
    session.addEventListener('end', () => this.ended());
    this.link.xr = { stateToSend: (state) => this.stateToSend(state) };
    session.requestAnimationFrame((t, f) => this.onFrame(t, f));
    this.onChange(true);
  }

  exit(): void {
    void this.session?.end().catch((e) => this.onError(`WebXR: ${(e as Error).message}`));
  }

  // Back to the desktop view: the store's state never held the session's views.
  private ended(): void {
    if (!this.session) return;
    this.session = null;
    this.layer = null;
    this.link.xr = null;
    this.onChange(false);
    this.link.send(false);
  }

  // The store's state as the session's: both eyes' views as a side-by-side pair of eye-sized images
  // (one view: mono).
  private stateToSend(state: RenderState): RenderState {
    if (this.views.length === 0) return state;
    state.camera.views = this.views.map((v) => JSON.parse(JSON.stringify(v)));
    state.stereo = { ...state.stereo, mode: this.views.length === 2 ? 'side-by-side' : 'off' };
    state.image = { ...this.eyeSize };
    return state;
  }

  private onFrame(_time: number, frame: XRFrameLike): void {
    const session = this.session, layer = this.layer, mapping = this.mapping;
    if (!session || !layer || !mapping) return;
    session.requestAnimationFrame((t, f) => this.onFrame(t, f));
    const pose = frame.getViewerPose(this.space);
    if (!pose) return;
    const eyes: { view: CameraView; viewport: Viewport }[] = [];
    for (const v of pose.views.slice(0, 2)) {
      const viewport = layer.getViewport(v);
      if (viewport) eyes.push({ view: viewOnPlanet(mapping, v), viewport });
    }
    if (eyes.length === 0) return;
    this.views = eyes.map((e) => e.view);
    const vp = eyes[0].viewport, scale = Math.min(1, kEyeMaxSide / Math.max(vp.width, vp.height));
    this.eyeSize = { width: Math.max(1, Math.round(vp.width * scale)), height: Math.max(1, Math.round(vp.height * scale)) };
    // A moved head asks for an interactive frame (when the server has answered, or kResendMs passed);
    // a head at rest for the still frame with all its passes, once.
    const key = JSON.stringify([this.views, this.eyeSize]);
    const now = performance.now();
    if (key !== this.sentKey) {
      if (this.link.caughtUp || now - this.lastSend > kResendMs) {
        this.sentKey = key;
        this.stillSent = false;
        this.lastSend = now;
        this.link.sendNow('interactive');
      }
    } else if (!this.stillSent && this.link.caughtUp) {
      this.stillSent = true;
      this.lastSend = now;
      this.link.sendNow('still');
    }
    const bg = (this.store.state.background as [number, number, number] | undefined) ?? [0, 0, 0];
    this.link.view.drawViews(layer.framebuffer, eyes, bg);
    this.framesDrawn++;
  }
}

// The "Enter VR" control: enabled when the browser offers immersive-vr; otherwise disabled and
// saying that WebXR immersive VR is not available here.
export async function setUpXr(button: HTMLButtonElement, link: RenderLink, store: StateStore,
  onError: (message: string) => void): Promise<XrSession | null> {
  const xr = (navigator as Navigator & { xr?: XRSystemLike }).xr;
  let offered = false;
  try {
    offered = xr ? await xr.isSessionSupported('immersive-vr') : false;
  } catch {
    offered = false;
  }
  if (!xr || !offered) {
    button.textContent = kNotAvailable;
    button.title = xr ? 'The browser has WebXR but offers no immersive-vr session (no headset)' : 'The browser has no navigator.xr';
    button.disabled = true;
    return null;
  }
  const session = new XrSession(link, store, (active) => {
    button.textContent = active ? 'Exit VR' : 'Enter VR';
  }, onError);
  button.textContent = 'Enter VR';
  button.title = `Head-tracked stereo in the headset: the view's eye at the start, 1 m = ${kKmPerMetre} km`;
  button.disabled = false;
  button.addEventListener('click', () => {
    if (session.active) session.exit();
    else session.enter(xr).catch((e) => onError(`WebXR: ${(e as Error).message}`));
  });
  return session;
}
