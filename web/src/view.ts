// The 3D view: shows the server's last frame, and while the camera differs from the one it was
// rendered with, re-projects it (image warping, as the paper): the frame's depth map becomes a
// vertex grid of world points (unprojected with the frame's camera), drawn with the current
// camera in WebGL2 and textured with the frame's JPEG. Where the depth map has no hit, the grid
// lies on a far sphere; triangles that mix hit and no-hit corners are dropped so the silhouette
// does not smear into the background. Disocclusions stretch (no hole filling).
// A stereo frame (docs/rendering.md, Stereo) is re-projected eye by eye: each eye's half of the
// depth map with that eye's camera, drawn with the current eye's camera into its half of the view
// (side by side) or into its colour channels (anaglyph: red the left eye, green and blue the right).
// A WebXR session (xr.ts) draws each eye of the last frame into its XRWebGLLayer viewport with the
// eye's current pose (drawViews), the same re-projection.
// Re-projection can be off (`reproject`; by default where WebGL runs in software, `softwareGl`):
// then the view shows each frame as the server rendered it, drawn once when it arrives. On a
// machine without a GPU every WebGL draw is rasterised and read back for the compositor on the CPU
// the server renders with: re-projecting at the display's rate took a core of the two and halved
// the frames a drag received (docs/ui.md, the section on speed).
import { CameraFrame, camerasEqual, stereoLayout, type CameraView, type EyeOffset } from './camera';
import type { CameraState, StereoState } from './state';
import type { Frame, FrameHeader } from './connection';

const kPlanetRadiusKm = 6371;
const kRimBlocks = 2;

const warpVs = `#version 300 es
in vec3 aPos;
in vec2 aUv;
in float aHit;
uniform vec3 uEye, uRight, uUp, uForward;
uniform float uTanHalfFovY, uAspect, uShiftX, uShiftY, uNear, uFar;
out vec2 vUv;
out float vHit;
void main() {
  vec3 d = aPos - uEye;
  float z = dot(d, uForward);
  float x = (dot(d, uRight) - uShiftX * z) / (uTanHalfFovY * uAspect);
  float y = (dot(d, uUp) - uShiftY * z) / uTanHalfFovY;
  float a = (uFar + uNear) / (uFar - uNear), b = -2.0 * uFar * uNear / (uFar - uNear);
  gl_Position = vec4(x, y, a * z + b, z);
  vUv = aUv;
  vHit = aHit;
}`;
const warpFs = `#version 300 es
precision highp float;
in vec2 vUv;
in float vHit;
uniform sampler2D uImage;
out vec4 outColor;
void main() {
  if (vHit > 0.001 && vHit < 0.999) discard;
  outColor = vec4(texture(uImage, vUv).rgb, 1.0);
}`;
const quadVs = `#version 300 es
in vec2 aXy;
out vec2 vUv;
void main() { vUv = vec2(aXy.x * 0.5 + 0.5, 0.5 - aXy.y * 0.5); gl_Position = vec4(aXy, 0.0, 1.0); }`;
const quadFs = `#version 300 es
precision highp float;
in vec2 vUv;
uniform sampler2D uImage;
out vec4 outColor;
void main() { outColor = vec4(texture(uImage, vUv).rgb, 1.0); }`;

function compile(gl: WebGL2RenderingContext, vs: string, fs: string): WebGLProgram {
  const program = gl.createProgram()!;
  for (const [type, src] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]] as const) {
    const s = gl.createShader(type)!;
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(`shader: ${gl.getShaderInfoLog(s)}`);
    gl.attachShader(program, s);
  }
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`shader link: ${gl.getProgramInfoLog(program)}`);
  return program;
}

// A view's viewport in the framebuffer, pixels from the bottom left (WebGL's, and XRViewport's).
export interface Viewport {
  x: number;
  y: number;
  width: number;
  height: number;
}

export interface ViewStats {
  warpedDraws: number;
  exactDraws: number;
  framesShown: number;
  // Draws into the canvas of any kind (a draw that would change nothing is skipped).
  glDraws: number;
}

// What a draw did: the frame drawn with its own camera, re-projected to the current one, drawn
// as it was rendered although the camera has changed since (re-projection off), or nothing to draw.
export type DrawKind = 'exact' | 'warped' | 'unwarped' | 'none';

// Renderer strings of WebGL implementations that run on the CPU.
const kSoftwareRenderers = /SwiftShader|llvmpipe|softpipe|Software Rasterizer|Microsoft Basic Render/i;

// The mesh of one view of a frame (the frame, or one eye of a stereo frame).
interface Mesh {
  vao: WebGLVertexArrayObject;
  buffer: WebGLBuffer;
  indexBuffer: WebGLBuffer;
  indexCount: number;
  key: string;
}

// The stereo fields a frame's views depend on ('off' for a mono frame).
function stereoKey(stereo: StereoState | undefined, camera: CameraState): string {
  if (!stereo || stereo.mode === 'off') return 'off';
  return `${stereo.mode}/${stereo.eyeSeparationKm}/${stereo.convergenceKm ?? camera.distanceKm}`;
}

export class View3D {
  private readonly gl: WebGL2RenderingContext;
  private readonly warpProgram: WebGLProgram;
  private readonly quadProgram: WebGLProgram;
  private readonly texture: WebGLTexture;
  private readonly meshes: Mesh[];
  private meshCount = 0; // of the frame shown: 1, or 2 for a stereo frame
  // The frame the meshes are of. A frame drawn with its own camera needs none (most still passes):
  // building them for every frame shown took 1.7 s of the main thread's 30 s of brushing at
  // 1920x1080 (a CPU profile, tests/browser/measure.mjs --profile).
  private meshFrame: Frame | null = null;
  private readonly quadVao: WebGLVertexArrayObject;
  private frame: Frame | null = null;
  // The header of the frame the view draws.
  get frameHeader(): FrameHeader | null { return this.frame?.header ?? null; }
  private size = { width: 1, height: 1 };
  readonly stats: ViewStats = { warpedDraws: 0, exactDraws: 0, framesShown: 0, glDraws: 0 };
  // The name of the rasteriser when WebGL runs on the CPU (from the unmasked renderer string where
  // the browser tells it), null on a GPU.
  readonly softwareGl: string | null;
  // Re-project the last frame to the current camera while a newer one is on its way (default: not
  // on a software GL). Set by the Rendering section's "Re-project" setting.
  reproject: boolean;
  // What the canvas shows (draw's key): a draw that would draw the same is skipped.
  private drawnKey = '';
  // Where the last draw put the frame's picture in the canvas, CSS pixels from the canvas's top
  // left (letterboxed); null before a frame. What the page writes over the picture goes there.
  pictureRect: { x: number; y: number; width: number; height: number } | null = null;

  constructor(readonly canvas: HTMLCanvasElement) {
    const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true, alpha: false });
    if (!gl) throw new Error('WebGL2 is not available in this browser');
    this.gl = gl;
    const info = gl.getExtension('WEBGL_debug_renderer_info');
    const renderer = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER) ?? '');
    this.softwareGl = kSoftwareRenderers.exec(renderer)?.[0] ?? null;
    this.reproject = this.softwareGl === null;
    this.warpProgram = compile(gl, warpVs, warpFs);
    this.quadProgram = compile(gl, quadVs, quadFs);
    this.texture = gl.createTexture()!;
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);

    this.meshes = [0, 1].map(() => {
      const mesh: Mesh = { vao: gl.createVertexArray()!, buffer: gl.createBuffer()!, indexBuffer: gl.createBuffer()!, indexCount: 0, key: '' };
      gl.bindVertexArray(mesh.vao);
      gl.bindBuffer(gl.ARRAY_BUFFER, mesh.buffer);
      const stride = 6 * 4;
      const attrib = (name: string, size: number, offset: number) => {
        const loc = gl.getAttribLocation(this.warpProgram, name);
        gl.enableVertexAttribArray(loc);
        gl.vertexAttribPointer(loc, size, gl.FLOAT, false, stride, offset);
      };
      attrib('aPos', 3, 0);
      attrib('aUv', 2, 12);
      attrib('aHit', 1, 20);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.indexBuffer);
      gl.bindVertexArray(null);
      return mesh;
    });

    this.quadVao = gl.createVertexArray()!;
    gl.bindVertexArray(this.quadVao);
    const qb = gl.createBuffer()!;
    gl.bindBuffer(gl.ARRAY_BUFFER, qb);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 1, -1, -1, 1, 1, 1]), gl.STATIC_DRAW);
    const ql = gl.getAttribLocation(this.quadProgram, 'aXy');
    gl.enableVertexAttribArray(ql);
    gl.vertexAttribPointer(ql, 2, gl.FLOAT, false, 0, 0);
    gl.bindVertexArray(null);
  }

  // The WebGL context (a WebXR session makes it XR-compatible and draws through drawViews).
  get context(): WebGL2RenderingContext {
    return this.gl;
  }

  get hasFrame(): boolean {
    return this.frame !== null;
  }
  get currentFrame(): Frame | null {
    return this.frame;
  }

  // The view's size in device pixels (its CSS size times devicePixelRatio): the size still frames
  // are drawn at.
  get fullWidth(): number { return this.size.width; }
  get fullHeight(): number { return this.size.height; }

  resize(width: number, height: number): void {
    this.size = { width, height };
    this.fitBuffer();
  }

  // The canvas' drawing buffer: the view's size, or half of it per axis while the frame shown is
  // an interactive or playback one of at most half the view's size per axis (a drag's frames are
  // 1/2 or 1/4 of it, docs/protocol.md). Nothing of such a frame is lost, and each display frame
  // of a drag has a quarter of the pixels to warp and to hand to the compositor (which in software
  // compositing reads the canvas back): more frames received and shown, docs/ui.md (the section
  // on speed).
  private fitBuffer(): void {
    const h = this.frame?.header;
    const { width, height } = this.size;
    const half = !!h && (h.interactive || h.playback) && 2 * h.width <= width + 1 && 2 * h.height <= height + 1;
    const w = half ? Math.ceil(width / 2) : width, hh = half ? Math.ceil(height / 2) : height;
    if (this.canvas.width !== w || this.canvas.height !== hh) {
      this.canvas.width = w;
      this.canvas.height = hh;
    }
  }

  // Decodes the frame's JPEG and makes it the one shown. One at a time: RenderLink waits for each.
  async setFrame(frame: Frame): Promise<void> {
    const bitmap = await createImageBitmap(frame.jpeg);
    const gl = this.gl;
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    gl.pixelStorei(gl.UNPACK_FLIP_Y_WEBGL, false);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGB, gl.RGB, gl.UNSIGNED_BYTE, bitmap);
    bitmap.close();
    this.frame = frame; // its meshes are built when a draw first warps it (beginWarp)
    this.fitBuffer();
    this.stats.framesShown++;
  }

  // A mesh per view of the frame: a stereo frame's depth map holds the eyes side by side (each
  // eyeWidth / depthWidth x 2 downsampled); its image holds them side by side or as an anaglyph.
  private buildMeshes(frame: Frame): void {
    const h = frame.header;
    const s = h.stereo;
    const views = h.camera.views ?? [];
    if (!s) {
      this.buildMesh(this.meshes[0], frame.depth, h.depthWidth, h.depthHeight, new CameraFrame(h.camera, h.width, h.height, undefined, views[0]), 0, 1);
      this.meshCount = 1;
      return;
    }
    const dw = h.depthWidth / 2, dh = h.depthHeight;
    for (let e = 0; e < 2; e++) {
      const depth = new Float32Array(dw * dh);
      for (let j = 0; j < dh; j++) depth.set(frame.depth.subarray(j * h.depthWidth + e * dw, j * h.depthWidth + (e + 1) * dw), j * dw);
      const eye: EyeOffset = { eyeOffsetKm: (e - 0.5) * s.eyeSeparationKm, convergenceKm: s.convergenceKm, pixelAspect: s.pixelAspect };
      const u0 = s.mode === 'anaglyph' ? 0 : e * 0.5, u1 = s.mode === 'anaglyph' ? 1 : u0 + 0.5;
      this.buildMesh(this.meshes[e], depth, dw, dh, new CameraFrame(h.camera, s.eyeWidth, s.eyeHeight, eye, views[e]), u0, u1);
    }
    this.meshCount = 2;
  }

  // One vertex per corner of the depth map's blocks, at the nearest finite depth of the blocks
  // that share the corner (the server's depth is the nearest finite depth per block); texture
  // u from u0 to u1 across the view.
  private buildMesh(mesh: Mesh, frameDepth: Float32Array, dw: number, dh: number, cam: CameraFrame, u0: number, u1: number): void {
    const eyeDist = Math.hypot(...cam.eye);
    const farT = eyeDist + 2 * kPlanetRadiusKm; // behind the planet, for pixels that hit nothing
    const nx = dw + 1, ny = dh + 1;
    // Blocks that hit nothing next to ones that did (the translucent rim of a feature, whose
    // opacity stayed below depthOpacity) take the nearest depth within kRimBlocks, so the rim
    // moves with its feature instead of staying on the far sphere.
    const depth = new Float32Array(frameDepth);
    for (let j = 0; j < dh; j++)
      for (let i = 0; i < dw; i++) {
        if (Number.isFinite(frameDepth[j * dw + i])) continue;
        let t = Infinity;
        for (let bj = Math.max(0, j - kRimBlocks); bj <= Math.min(dh - 1, j + kRimBlocks); bj++)
          for (let bi = Math.max(0, i - kRimBlocks); bi <= Math.min(dw - 1, i + kRimBlocks); bi++) {
            const v = frameDepth[bj * dw + bi];
            if (v < t) t = v;
          }
        depth[j * dw + i] = t;
      }
    const data = new Float32Array(nx * ny * 6);
    for (let j = 0; j < ny; j++) {
      for (let i = 0; i < nx; i++) {
        let t = Infinity;
        for (let bj = Math.max(0, j - 1); bj <= Math.min(dh - 1, j); bj++)
          for (let bi = Math.max(0, i - 1); bi <= Math.min(dw - 1, i); bi++) {
            const v = depth[bj * dw + bi];
            if (Number.isFinite(v) && v < t) t = v;
          }
        const hit = Number.isFinite(t);
        const px = (i * cam.width) / dw, py = (j * cam.height) / dh;
        const d = cam.direction(px, py);
        const tt = hit ? t : farT;
        const o = (j * nx + i) * 6;
        data[o] = cam.eye[0] + d[0] * tt;
        data[o + 1] = cam.eye[1] + d[1] * tt;
        data[o + 2] = cam.eye[2] + d[2] * tt;
        data[o + 3] = u0 + ((u1 - u0) * i) / dw;
        data[o + 4] = j / dh;
        data[o + 5] = hit ? 1 : 0;
      }
    }
    const gl = this.gl;
    gl.bindVertexArray(mesh.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, mesh.buffer);
    gl.bufferData(gl.ARRAY_BUFFER, data, gl.DYNAMIC_DRAW);
    const key = `${dw}x${dh}`;
    if (key !== mesh.key) {
      const idx = new Uint32Array(dw * dh * 6);
      let k = 0;
      for (let j = 0; j < dh; j++)
        for (let i = 0; i < dw; i++) {
          const a = j * nx + i, b = a + 1, c = a + nx, e = c + 1;
          idx[k++] = a; idx[k++] = c; idx[k++] = b;
          idx[k++] = b; idx[k++] = c; idx[k++] = e;
        }
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.indexBuffer);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx, gl.STATIC_DRAW);
      mesh.indexCount = idx.length;
      mesh.key = key;
    }
    gl.bindVertexArray(null);
  }

  // Draws the last frame for `camera` and `stereo` at image size width x height (each eye's, as the
  // state's image; letterboxed into the canvas as the composed picture). Returns 'exact' when the
  // frame's own camera, stereo views and size match, 'warped' when re-projected, 'unwarped' when
  // they differ and re-projection is off (the frame is shown letterboxed as rendered).
  draw(camera: CameraState, stereo: StereoState | undefined, width: number, height: number,
    background: [number, number, number]): DrawKind {
    const frame = this.frame;
    const layout = stereoLayout(stereo, camera, width, height);
    const h = frame?.header;
    const frameStereo = h?.stereo ? stereoKey({ mode: h.stereo.mode, eyeSeparationKm: h.stereo.eyeSeparationKm, convergenceKm: h.stereo.convergenceKm }, h.camera) : 'off';
    const exact = !!h && camerasEqual(camera, h.camera) && stereoKey(stereo, camera) === frameStereo &&
      layout.width * h.height === layout.height * h.width;
    const kind: DrawKind = !frame ? 'none' : exact ? 'exact' : this.reproject ? 'warped' : 'unwarped';
    // What the canvas will show; the same as shown already: nothing to draw. (An exact or unwarped
    // frame is the frame's picture whatever the camera; a warped one is drawn for each camera.)
    const key = JSON.stringify([this.stats.framesShown, this.canvas.width, this.canvas.height, background,
      kind === 'warped' ? [kind, camera, stereoKey(stereo, camera), layout.width, layout.height] : h ? ['frame', h.width, h.height] : kind]);
    if (key === this.drawnKey) return kind;
    this.drawnKey = key;
    this.stats.glDraws++;
    const gl = this.gl;
    const cw = this.canvas.width, ch = this.canvas.height;
    gl.viewport(0, 0, cw, ch);
    gl.colorMask(true, true, true, true);
    gl.clearColor(background[0], background[1], background[2], 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    if (!frame || !h) return 'none';
    // Fit the composed image's aspect (the frame's own when it is shown as rendered) into the canvas.
    const aspect = kind === 'unwarped' ? h.width / h.height : layout.width / layout.height;
    let vw = cw, vh = Math.round(cw / aspect);
    if (vh > ch) { vh = ch; vw = Math.round(ch * aspect); }
    const vx = Math.floor((cw - vw) / 2), vy = Math.floor((ch - vh) / 2);
    const cssPerPx = this.canvas.clientWidth / cw || 1;
    this.pictureRect = { x: vx * cssPerPx, y: (ch - vy - vh) * cssPerPx, width: vw * cssPerPx, height: vh * cssPerPx };
    gl.viewport(vx, vy, vw, vh);
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    if (kind !== 'warped') {
      gl.useProgram(this.quadProgram);
      gl.disable(gl.DEPTH_TEST);
      gl.bindVertexArray(this.quadVao);
      gl.drawArrays(gl.TRIANGLE_STRIP, 0, 4);
      gl.bindVertexArray(null);
      if (kind === 'exact') this.stats.exactDraws++;
      return kind;
    }
    this.beginWarp();
    const sideBySide = layout.mode === 'side-by-side' || layout.mode === 'side-by-side-half';
    const views = camera.views ?? [];
    layout.eyes.forEach((eye, e) => {
      // Each eye of the view from the frame's view of the same eye (a mono frame serves both).
      if (sideBySide) gl.viewport(vx + (e * vw) / 2, vy, vw / 2, vh);
      if (layout.mode === 'anaglyph') gl.colorMask(e === 0, e === 1, e === 1, true);
      this.drawMesh(e, new CameraFrame(camera, eye.width, eye.height, eye, views[e]));
    });
    gl.bindVertexArray(null);
    gl.colorMask(true, true, true, true);
    this.stats.warpedDraws++;
    return 'warped';
  }

  // Draws the last frame into `framebuffer` (null: the canvas) once per view, each re-projected to
  // its current pose and frustum in its viewport: view e from the frame's eye e (a mono frame serves
  // both). Returns false when there is no frame yet (the viewports are cleared).
  drawViews(framebuffer: WebGLFramebuffer | null, views: { view: CameraView; viewport: Viewport }[],
    background: [number, number, number]): boolean {
    const gl = this.gl;
    this.drawnKey = ''; // the canvas is drawn anew when the session ends
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
    gl.colorMask(true, true, true, true);
    gl.clearColor(background[0], background[1], background[2], 1);
    gl.enable(gl.SCISSOR_TEST);
    for (const { viewport: v } of views) {
      gl.viewport(v.x, v.y, v.width, v.height);
      gl.scissor(v.x, v.y, v.width, v.height);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    }
    gl.disable(gl.SCISSOR_TEST);
    const frame = this.frame;
    if (frame) {
      gl.bindTexture(gl.TEXTURE_2D, this.texture);
      this.beginWarp();
      views.forEach(({ view, viewport: v }, e) => {
        gl.viewport(v.x, v.y, v.width, v.height);
        this.drawMesh(e, new CameraFrame(frame.header.camera, v.width, v.height, undefined, view));
      });
      gl.bindVertexArray(null);
      this.stats.warpedDraws++;
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return frame !== null;
  }

  private beginWarp(): void {
    if (this.frame && this.meshFrame !== this.frame) {
      this.buildMeshes(this.frame);
      this.meshFrame = this.frame;
    }
    const gl = this.gl;
    gl.useProgram(this.warpProgram);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LEQUAL);
  }

  // The mesh of the frame's view e (the last one when the frame has fewer) drawn with camera `cam`
  // into the current viewport.
  private drawMesh(e: number, cam: CameraFrame): void {
    const gl = this.gl, p = this.warpProgram;
    const mesh = this.meshes[Math.min(e, this.meshCount - 1)];
    gl.clear(gl.DEPTH_BUFFER_BIT);
    gl.uniform3fv(gl.getUniformLocation(p, 'uEye'), cam.eye);
    gl.uniform3fv(gl.getUniformLocation(p, 'uRight'), cam.right);
    gl.uniform3fv(gl.getUniformLocation(p, 'uUp'), cam.up);
    gl.uniform3fv(gl.getUniformLocation(p, 'uForward'), cam.forward);
    gl.uniform1f(gl.getUniformLocation(p, 'uTanHalfFovY'), cam.tanHalfFovY);
    gl.uniform1f(gl.getUniformLocation(p, 'uAspect'), cam.aspect);
    gl.uniform1f(gl.getUniformLocation(p, 'uShiftX'), cam.shiftX);
    gl.uniform1f(gl.getUniformLocation(p, 'uShiftY'), cam.shiftY);
    const eyeDist = Math.hypot(...cam.eye);
    gl.uniform1f(gl.getUniformLocation(p, 'uNear'), Math.max(1, (eyeDist - 3 * kPlanetRadiusKm) * 0.5));
    gl.uniform1f(gl.getUniformLocation(p, 'uFar'), eyeDist + 8 * kPlanetRadiusKm + 1e5);
    gl.bindVertexArray(mesh.vao);
    gl.drawElements(gl.TRIANGLES, mesh.indexCount, gl.UNSIGNED_INT, 0);
  }
}
