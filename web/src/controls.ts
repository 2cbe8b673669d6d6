// The controls that are neither a panel nor the view: the Rendering section, the header's Save /
// Load / Copy link, the time bar, the keyboard and the page URL.
import { cloneState, encodeStateForUrl, stateFromHash } from './state';
import type { StateStore } from './store';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

export interface ControlsHost {
  commit(interactive: boolean): void;
  loadState(doc: unknown): void;
  loadOutsideState(doc: unknown, what: string): Promise<void>;
  showError(message: string): void;
  setStatusNote(text: string): void;
  setStep(step: number, interactive: boolean): void;
  togglePlay(): void;
  stopPlaying(): void;
  cancelRendering(): void;
  // The image size follows the view again; true when it changed.
  fitImage(): boolean;
  clearBrushes(): void;
  // The 3D view's re-projection (view.ts) and the WebGL it runs on; redrawView after a change.
  readonly view: { reproject: boolean; readonly softwareGl: string | null };
  redrawView(): void;
}

const kMaxSizeKey = 'raypc.maxImageSide';
const kReprojectKey = 'raypc.reproject';

// The cap on the longer side of still frames (the Max size setting; default 4096 pixels).
export function maxImageSide(): number {
  return Number($<HTMLSelectElement>('maxSize').value) || 4096;
}

// Calls `read` with the text of the file chosen in a file input (then clears the input, so the same
// file can be chosen again); an error of `read` is shown naming the file (`what` before its name).
export function onFileChosen(input: HTMLInputElement, what: string, read: (text: string, name: string) => void,
  showError: (message: string) => void): void {
  input.addEventListener('change', async () => {
    const file = input.files?.[0];
    input.value = '';
    if (!file) return;
    try {
      read(await file.text(), file.name);
    } catch (err) {
      showError(`${what}${file.name}: ${(err as Error).message}`);
    }
  });
}

export function download(blob: Blob, name: string): void {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

export function setUpControls(store: StateStore, host: ControlsHost): void {
  const info = store.info;
  $('dataset').textContent = `${info.name} · ${info.steps.length} steps · ${info.variables.length} variables · sample of ${info.sample.rows.toLocaleString()} points`;
  document.title = `RayPC · ${info.name}`;
  // The cap on the still frame's longer side (a setting of this browser, not of the state).
  const maxSize = $<HTMLSelectElement>('maxSize');
  const savedMax = localStorage.getItem(kMaxSizeKey);
  if (savedMax && [...maxSize.options].some((o) => o.value === savedMax)) maxSize.value = savedMax;
  maxSize.addEventListener('change', () => {
    localStorage.setItem(kMaxSizeKey, maxSize.value);
    store.autoFitImage = true;
    if (host.fitImage()) host.commit(false);
  });
  // Re-projection while a frame is on its way (a setting of this browser): auto is off where WebGL
  // runs in software, as the note beside it says.
  const reproject = $<HTMLSelectElement>('reproject');
  const savedReproject = localStorage.getItem(kReprojectKey);
  if (savedReproject && [...reproject.options].some((o) => o.value === savedReproject)) reproject.value = savedReproject;
  const applyReproject = () => {
    const v = host.view;
    v.reproject = reproject.value === 'on' || (reproject.value === 'auto' && v.softwareGl === null);
    $('reprojectNote').textContent = reproject.value === 'auto'
      ? (v.softwareGl !== null ? `(off: WebGL runs in software, ${v.softwareGl})` : '(on)') : '';
    host.redrawView();
  };
  applyReproject();
  reproject.addEventListener('change', () => {
    localStorage.setItem(kReprojectKey, reproject.value);
    applyReproject();
  });
  $('passes').addEventListener('change', () => {
    const v = Math.round(Number($<HTMLInputElement>('passes').value));
    if (v >= 1) {
      store.state.passes = v;
      host.commit(false);
    }
  });
  $('level').addEventListener('change', () => {
    const v = $<HTMLSelectElement>('level').value;
    store.state.level = v === 'auto' ? 'auto' : Number(v);
    host.commit(false);
  });
  $('lighting').addEventListener('change', () => {
    store.state.shading = { ...store.state.shading, enabled: $<HTMLInputElement>('lighting').checked };
    enableLightControls(store);
    host.commit(false);
  });
  $('shadows').addEventListener('change', () => {
    store.state.shading = { ...store.state.shading, shadows: $<HTMLInputElement>('shadows').checked };
    enableLightControls(store);
    host.commit(false);
  });
  // The light's direction (azimuth, elevation in the camera frame) and the highlight's weight:
  // interactive while dragged, a still frame on release (a restart of the passes either way).
  const lightInput = (interactive: boolean) => {
    const az = Number($<HTMLInputElement>('lightAzimuth').value), el = Number($<HTMLInputElement>('lightElevation').value);
    store.state.shading = {
      ...store.state.shading,
      light: lightFromAngles(az, el),
      specular: Number($<HTMLInputElement>('lightSpecular').value),
      shadowStrength: Number($<HTMLInputElement>('shadowStrength').value),
    };
    showLightAngles(az, el);
    host.commit(interactive);
  };
  for (const id of ['lightAzimuth', 'lightElevation', 'lightSpecular', 'shadowStrength']) {
    $(id).addEventListener('input', () => lightInput(true));
    $(id).addEventListener('change', () => lightInput(false));
  }
  // Stereo (state key stereo): the server renders both eyes; the view re-projects each.
  const stereoInput = () => {
    const separation = Number($<HTMLInputElement>('stereoSeparation').value);
    const convergenceText = $<HTMLInputElement>('stereoConvergence').value.trim();
    const convergence = Number(convergenceText);
    store.state.stereo = {
      mode: $<HTMLSelectElement>('stereoMode').value,
      eyeSeparationKm: Number.isFinite(separation) && separation >= 0 ? separation : store.state.stereo.eyeSeparationKm,
      convergenceKm: convergenceText === '' || !(convergence > 0) ? null : convergence,
    };
    if (store.autoFitImage) host.fitImage();
    host.commit(false);
  };
  for (const id of ['stereoMode', 'stereoSeparation', 'stereoConvergence']) $(id).addEventListener('change', stereoInput);
  $('core').addEventListener('change', () => {
    store.state.core = { ...store.state.core, visible: $<HTMLInputElement>('core').checked };
    host.commit(false);
  });
  $('cancel').addEventListener('click', () => {
    host.stopPlaying();
    host.cancelRendering();
    host.setStatusNote('cancelled');
  });
  $('resetView').addEventListener('click', () => {
    store.state.camera = cloneState(store.defaults).camera;
    host.commit(false);
  });
  $('clearBrushes').addEventListener('click', () => host.clearBrushes());
  const stepIn = $<HTMLInputElement>('step');
  stepIn.max = String(info.steps.length - 1);
  stepIn.addEventListener('input', () => host.setStep(Number(stepIn.value), true));
  stepIn.addEventListener('change', () => host.setStep(Number(stepIn.value), false));
  $('play').addEventListener('click', () => host.togglePlay());
  // "?" (or the header's ? button) shows the mouse and keyboard help.
  const help = $<HTMLDialogElement>('helpDialog');
  $('help').addEventListener('click', () => help.showModal());
  $('helpClose').addEventListener('click', () => help.close());
  document.addEventListener('keydown', (e) => {
    const t = e.target as HTMLElement;
    if (e.key === '?' && !(t instanceof HTMLInputElement || t instanceof HTMLSelectElement) && !document.querySelector('dialog[open]')) {
      e.preventDefault();
      help.showModal();
      return;
    }
    if (e.key === ' ' && !(t instanceof HTMLInputElement || t instanceof HTMLSelectElement || t instanceof HTMLButtonElement)) {
      e.preventDefault();
      host.togglePlay();
    }
  });

  $('save').addEventListener('click', () => {
    download(new Blob([JSON.stringify(store.state, null, 2) + '\n'], { type: 'application/json' }), `raypc-state-step${store.state.step}.json`);
  });
  onFileChosen($<HTMLInputElement>('load'), '', (text, name) => {
    void host.loadOutsideState(JSON.parse(text), name);
  }, (m) => host.showError(m));
  $('share').addEventListener('click', async () => {
    const url = `${location.origin}${location.pathname}${location.search}#state=${encodeStateForUrl(store.state)}`;
    try {
      await navigator.clipboard.writeText(url);
      host.setStatusNote('link copied');
    } catch {
      window.prompt('Link to this view:', url);
    }
  });
  window.addEventListener('hashchange', () => {
    try {
      const s = stateFromHash(location.hash);
      if (s && JSON.stringify(s) !== JSON.stringify(store.state)) void host.loadOutsideState(s, 'the state in the URL');
    } catch (e) {
      host.showError(`state in the URL: ${(e as Error).message}`);
    }
  });
}

// Puts the state into the controls of this module (after load, preset, URL).
export function syncControls(store: StateStore): void {
  const s = store.state;
  $<HTMLInputElement>('passes').value = String(s.passes);
  $<HTMLSelectElement>('level').value = String(s.level);
  $<HTMLInputElement>('lighting').checked = Boolean((s.shading as { enabled?: boolean } | undefined)?.enabled);
  const [az, el] = anglesFromLight(s.shading.light);
  $<HTMLInputElement>('lightAzimuth').value = String(Math.round(az));
  $<HTMLInputElement>('lightElevation').value = String(Math.round(el));
  $<HTMLInputElement>('lightSpecular').value = String(s.shading.specular);
  $<HTMLInputElement>('shadows').checked = Boolean(s.shading.shadows);
  $<HTMLInputElement>('shadowStrength').value = String(s.shading.shadowStrength);
  showLightAngles(az, el);
  enableLightControls(store);
  $<HTMLInputElement>('core').checked = (s.core as { visible?: boolean } | undefined)?.visible !== false;
  $<HTMLSelectElement>('stereoMode').value = s.stereo.mode;
  $<HTMLInputElement>('stereoSeparation').value = String(s.stereo.eyeSeparationKm);
  $<HTMLInputElement>('stereoConvergence').value = s.stereo.convergenceKm === null ? '' : String(s.stereo.convergenceKm);
  $<HTMLInputElement>('step').value = String(s.step);
}

// The direction towards the light in the camera frame (x right, y up, z towards the viewer; the
// state's shading.light) from its azimuth (degrees from the viewing direction, +z, towards the
// right, +x) and elevation (degrees above the image's horizontal plane, towards +y). A unit vector.
export function lightFromAngles(azimuthDeg: number, elevationDeg: number): [number, number, number] {
  const az = (azimuthDeg * Math.PI) / 180, el = (elevationDeg * Math.PI) / 180;
  const round = (v: number) => Math.round(v * 1e6) / 1e6;
  return [round(Math.cos(el) * Math.sin(az)), round(Math.sin(el)), round(Math.cos(el) * Math.cos(az))];
}

// The inverse of lightFromAngles for any non-zero vector: [azimuth, elevation] in degrees.
export function anglesFromLight(light: readonly number[]): [number, number] {
  const [x, y, z] = light;
  const len = Math.hypot(x, y, z) || 1;
  return [(Math.atan2(x, z) * 180) / Math.PI, (Math.asin(Math.max(-1, Math.min(1, y / len))) * 180) / Math.PI];
}

function showLightAngles(azimuthDeg: number, elevationDeg: number): void {
  $('lightAzimuthValue').textContent = `${Math.round(azimuthDeg)}°`;
  $('lightElevationValue').textContent = `${Math.round(elevationDeg)}°`;
}

// The light's controls mean nothing while lighting and shadows are off (its direction casts the
// shadows, so it stays live with shadows alone); the highlight needs lighting, the strength shadows.
function enableLightControls(store: StateStore): void {
  const lit = Boolean(store.state.shading.enabled), shadowed = Boolean(store.state.shading.shadows);
  const off = !lit && !shadowed;
  for (const id of ['lightAzimuth', 'lightElevation']) $<HTMLInputElement>(id).disabled = off;
  $<HTMLInputElement>('lightSpecular').disabled = !lit;
  $<HTMLInputElement>('shadowStrength').disabled = !shadowed;
  $('lightRow').classList.toggle('disabled', off);
}

// The URL of the page holds the state (#state=…) so that a bookmark reopens this view.
export function writeStateToUrl(store: StateStore): void {
  history.replaceState(null, '', `${location.pathname}${location.search}#state=${encodeStateForUrl(store.state)}`);
}
