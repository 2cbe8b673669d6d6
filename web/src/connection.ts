// The WebSocket side of docs/protocol.md: hello, whole states with a client id, cancel, and
// binary frames (u32 header length, JSON header, JPEG, float32 depth map). Reconnects after a
// drop and resends the last state, so a restarted server picks the view up again. The server's
// text messages: hello, error, pong, and link (a state a program set through POST /api/link).
import type { RenderState } from './state';
import type {
  ClientCancel, ClientHello, ClientState, FrameHeader, ServerError, ServerHello, ServerLink, ServerPong,
} from './generated/protocol_types';

// The server's messages are typed from their one description (src/server/protocol_schema.cpp).
export type { FrameHeader, ShellKeyEntry } from './generated/protocol_types';
// How the server renders a state (docs/protocol.md, the state message): a still state's passes,
// one interactive pass, or a step of playback.
export type SendMode = 'still' | 'interactive' | 'playback';

export interface Frame {
  header: FrameHeader;
  jpeg: Blob;
  depth: Float32Array; // depthWidth x depthHeight, km along the ray, +Infinity = nothing hit
  receivedAt: number;
}

export function decodeFrame(buffer: ArrayBuffer): Frame {
  const view = new DataView(buffer);
  if (buffer.byteLength < 4) throw new Error(`frame: ${buffer.byteLength} bytes, shorter than its length prefix`);
  const headerBytes = view.getUint32(0, true);
  if (4 + headerBytes > buffer.byteLength) throw new Error(`frame: header of ${headerBytes} bytes past the end`);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, headerBytes))) as FrameHeader;
  const jpegStart = 4 + headerBytes;
  const depthStart = jpegStart + header.jpegBytes;
  const depthCount = header.depthWidth * header.depthHeight;
  if (header.depthBytes !== depthCount * 4 || depthStart + header.depthBytes > buffer.byteLength)
    throw new Error(`frame ${header.id}: sizes do not add up (jpeg ${header.jpegBytes}, depth ${header.depthBytes}, message ${buffer.byteLength})`);
  const jpeg = new Blob([new Uint8Array(buffer, jpegStart, header.jpegBytes)], { type: 'image/jpeg' });
  // The depth map need not be 4-byte aligned in the message: copy it out.
  const depth = new Float32Array(buffer.slice(depthStart, depthStart + header.depthBytes));
  return { header, jpeg, depth, receivedAt: performance.now() };
}

// The server's text messages (docs/protocol.md, Server → client).
type ServerText = ServerHello | ServerError | ServerPong | ServerLink;

export interface ConnectionEvents {
  onFrame(frame: Frame): void;
  onError(message: string, id?: number): void;
  onStatus(text: string): void;
  // A state a program set (POST /api/link), unchecked: to be applied as a state from outside the page.
  onLink(state: unknown, version: number): void;
}

export class Connection {
  private ws: WebSocket | null = null;
  private nextId = 1;
  private lastSent: { state: RenderState; mode: SendMode } | null = null;
  private open = false;
  private retryMs = 500;
  lastSentId = 0;
  lastFrameId = 0;

  private closed = false;

  // `dataset`: which dataset of a pair the session renders (docs/compare.md; 0 the first or only one).
  constructor(private readonly events: ConnectionEvents, private readonly dataset = 0) {
    this.connect();
  }

  // Closes the session for good (a pair's second view closed): no reconnection.
  close(): void {
    this.closed = true;
    this.ws?.close();
  }

  private connect(): void {
    const url = new URL('ws', location.href);
    url.protocol = location.protocol === 'https:' ? 'wss:' : 'ws:';
    const token = new URLSearchParams(location.search).get('token');
    if (token) url.searchParams.set('token', token);
    if (this.dataset) url.searchParams.set('dataset', String(this.dataset));
    const ws = new WebSocket(url.toString());
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    ws.onopen = () => {
      ws.send(JSON.stringify({ type: 'hello', protocol: 1 } satisfies ClientHello));
    };
    ws.onmessage = (ev) => {
      if (typeof ev.data === 'string') {
        let msg: ServerText;
        try {
          msg = JSON.parse(ev.data);
        } catch {
          this.events.onError(`server sent text that is not JSON: ${String(ev.data).slice(0, 80)}`);
          return;
        }
        if (msg.type === 'hello') {
          this.open = true;
          this.retryMs = 500;
          this.events.onStatus('connected');
          if (this.lastSent) this.sendNow(this.lastSent.state, this.lastSent.mode);
        } else if (msg.type === 'error') {
          // A refused state gets no frame: count it as answered so playback does not wait for it.
          if (typeof msg.id === 'number') this.lastFrameId = Math.max(this.lastFrameId, msg.id);
          this.events.onError(msg.message ?? 'error', msg.id);
        } else if (msg.type === 'link') {
          this.events.onLink(msg.state, msg.version);
        }
        return;
      }
      try {
        const frame = decodeFrame(ev.data as ArrayBuffer);
        this.lastFrameId = Math.max(this.lastFrameId, frame.header.id);
        this.events.onFrame(frame);
      } catch (e) {
        this.events.onError((e as Error).message);
      }
    };
    ws.onclose = () => {
      this.open = false;
      this.ws = null;
      if (this.closed) return;
      this.events.onStatus(`disconnected; retrying in ${(this.retryMs / 1000).toFixed(1)} s`);
      setTimeout(() => this.connect(), this.retryMs);
      this.retryMs = Math.min(8000, this.retryMs * 2);
    };
  }

  // Sends the whole state; returns its id (frames echo it).
  send(state: RenderState, mode: SendMode): number {
    this.lastSent = { state, mode };
    return this.open ? this.sendNow(state, mode) : this.nextId;
  }

  private sendNow(state: RenderState, mode: SendMode): number {
    const id = this.nextId++;
    this.lastSentId = id;
    this.ws?.send(JSON.stringify({ type: 'state', id, state, interactive: mode === 'interactive', playback: mode === 'playback' } satisfies ClientState));
    return id;
  }

  cancel(): void {
    if (this.open) this.ws?.send(JSON.stringify({ type: 'cancel' } satisfies ClientCancel));
  }

  // True when the newest sent state has been answered by at least one frame.
  get caughtUp(): boolean {
    return this.lastFrameId >= this.lastSentId;
  }
}
