// The Screenshot dialog: the user picks the picture's size — the view's (the still frame's size),
// twice that, 4K (3840 pixels wide) or a custom width × height — and the server renders the state
// converged at that size at full resolution (POST /api/screenshot: all passes, level 0). Sizes keep
// the view's aspect except a custom one (the camera's vertical field of view stays, so a wider
// picture shows more on the sides).
import { postScreenshot } from './api';
import { cloneState, type RenderState } from './state';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

// The state document's bound on image.width and image.height (state_schema.cpp).
export const kMaxImageSide = 16384;

export interface ScreenshotHost {
  state(): RenderState;
  showError(message: string): void;
  setStatusNote(text: string): void;
  download(blob: Blob, name: string): void;
  fileStem(): string;
  limits(): { screenshotPixels: number; screenshotPasses: number; screenshotPixelPasses: number };
}

// The most pixels the server renders for a screenshot of `passes` passes (its limits, GET /api/info).
export function maxScreenshotPixels(limits: ReturnType<ScreenshotHost['limits']>, passes: number): number {
  return Math.min(limits.screenshotPixels, Math.floor(limits.screenshotPixelPasses / Math.max(1, passes)));
}

export type ShotChoice = 'view' | '2x' | '4k' | 'custom';

// The picture's size for a choice, from the still frame's size (the view × devicePixelRatio).
export function screenshotSize(choice: ShotChoice, image: { width: number; height: number },
  custom: { width: number; height: number }): { width: number; height: number } {
  const scaled = (w: number) => ({ width: w, height: Math.max(1, Math.round((w * image.height) / image.width)) });
  switch (choice) {
    case 'view': return { ...image };
    case '2x': return { width: image.width * 2, height: image.height * 2 };
    case '4k': return scaled(3840);
    case 'custom': return { ...custom };
  }
}

export function setUpScreenshot(host: ScreenshotHost): void {
  const dialog = $<HTMLDialogElement>('shotDialog');
  const choice = () => (document.querySelector<HTMLInputElement>('input[name="shotSize"]:checked')?.value ?? 'view') as ShotChoice;
  const custom = () => ({ width: Math.round(Number($<HTMLInputElement>('shotWidth').value)), height: Math.round(Number($<HTMLInputElement>('shotHeight').value)) });
  const label = (id: string, size: { width: number; height: number }) => { $(id).textContent = `${size.width} × ${size.height}`; };
  $('screenshot').addEventListener('click', () => {
    const image = host.state().image;
    label('shotViewSize', screenshotSize('view', image, image));
    label('shot2xSize', screenshotSize('2x', image, image));
    label('shot4kSize', screenshotSize('4k', image, image));
    const most = maxScreenshotPixels(host.limits(), host.state().passes);
    const side = Math.floor(Math.sqrt(most));
    $('shotLimit').textContent = `The server renders at most ${most.toLocaleString('en')} pixels at this state's ${host.state().passes} passes (e.g. ${side} × ${side}).`;
    if (!$<HTMLInputElement>('shotWidth').value) {
      $<HTMLInputElement>('shotWidth').value = String(image.width);
      $<HTMLInputElement>('shotHeight').value = String(image.height);
    }
    dialog.showModal();
  });
  $('shotCancel').addEventListener('click', () => dialog.close());
  $('shotRender').addEventListener('click', async () => {
    const size = screenshotSize(choice(), host.state().image, custom());
    if (!(size.width >= 1 && size.height >= 1 && size.width <= kMaxImageSide && size.height <= kMaxImageSide)) {
      host.showError(`screenshot size ${size.width} × ${size.height}: each side must be 1 … ${kMaxImageSide} pixels`);
      return;
    }
    const most = maxScreenshotPixels(host.limits(), host.state().passes);
    if (size.width * size.height > most) {
      host.showError(`screenshot size ${size.width} × ${size.height}: more than the ${most.toLocaleString('en')} pixels the server renders at ${host.state().passes} passes`);
      return;
    }
    dialog.close();
    const button = $<HTMLButtonElement>('screenshot');
    button.disabled = true;
    host.setStatusNote(`rendering a ${size.width} × ${size.height} screenshot…`);
    try {
      // Converged at full resolution: level "auto" is level 0 for a still picture.
      const state = { ...cloneState(host.state()), image: size, level: 'auto' as const };
      host.download(await postScreenshot(state), `${host.fileStem()}-${size.width}x${size.height}.png`);
      host.setStatusNote(`screenshot ${size.width} × ${size.height} saved`);
    } catch (err) {
      host.setStatusNote(`screenshot ${size.width} × ${size.height} failed`);
      host.showError((err as Error).message);
    } finally {
      button.disabled = false;
    }
  });
}
