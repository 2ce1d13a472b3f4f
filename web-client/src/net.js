// The WebSocket link to the server: hello with the protocol version and the
// page's token, JSON events and binary geometry frames, reconnect with
// backoff after the server goes away. Requests carry a `req` number and are
// answered by `ack` or `error`.

import { decodeFrame, PROTOCOL_VERSION } from './frame.js';
import { DragStream } from './drag-stream.js';
import { isDeflated, inflateMessage } from './deflated.js';
import { MeshDeltas } from './dsm-delta.js';

/** Why the server refused to let this page join, said so a person knows what to do; the link then stays closed. */
export const REFUSALS = {
  bad_token: (design) => `this link's token is not valid for design ${design}: ask the designer for a new link`,
  unknown_design: (design) => `design ${design} does not exist on this server: check the link`,
  bad_version: () => 'this page and the server speak different protocol versions: reload the page (Ctrl+Shift+R)',
  bad_handshake: () => 'the server did not accept this page\'s greeting: reload it',
};

/**
 * The link's capabilities, in its URL: drag_stream=1, a drag comes as ρ once and d per frame
 * (protocol/README.md, "Drag stream"); deflate=1, large binary messages come deflated (kind 7,
 * "Deflated message"); pace=1, geometry at the rate this link carries ("Paced delivery"), for
 * which the page reports the binary bytes it has received; mesh_delta=1, a re-meshed part comes
 * as the changes from its last mesh frame ("Binary mesh delta (kind 8)"). index.html opens its
 * early socket with the same query.
 */
export const LINK_QUERY = 'drag_stream=1&deflate=1&pace=1&mesh_delta=1';

/** How long the first hello waits for the geometry cache's answer (an IndexedDB read takes a few ms). */
const CACHE_WAIT_MS = 500;

/** `p`, or null after `ms`. */
const withTimeout = (p, ms) => Promise.race([p, new Promise((resolve) => setTimeout(() => resolve(null), ms))]);

export class Link {
  /**
   * `cache` (a GeometryCache, or null): this design's frames kept from the last visit are drawn
   * at once, their name goes in the first hello, and each compact join's frames are kept for the next.
   */
  constructor({ design, token, name, onMessage, onFrame, onStatus, onHello = () => {}, cache = null }) {
    this.design = design;
    this.cache = cache;
    /** What the geometry cache did on this page: frames drawn from it, the name offered, whether the server confirmed it (null until the welcome). */
    this.cacheUse = { replayed: 0, kinds: [], offered: null, confirmed: null, saved: null };
    /** Called each time a hello has been sent (the page prepares its first picture meanwhile). */
    this.onHello = onHello;
    this.token = token;
    this.name = name;
    this.onMessage = onMessage;
    this.onFrame = onFrame;
    this.onStatus = onStatus;
    this.req = 0;
    this.backoff = 250;
    this.ws = null;
    this.closedByServer = false;
    this.refusal = null;
    this.welcomed = false;
    this.connections = 0;
    // The kept frames are drawn as soon as they are read (the first connection's frame path, so a
    // mesh frame is the base of later deltas as if it had come now); the first hello waits for them.
    this.cached = (cache ? withTimeout(cache.load(design), CACHE_WAIT_MS) : Promise.resolve(null)).then((entry) => {
      if (!entry || this.welcomed) return null;
      let read = 0;
      for (const f of entry.frames) {
        // The kinds drawn (byte 4 of each frame): app.js prewarms the programs they need.
        const kind = f.byteLength > 4 ? new Uint8Array(f)[4] : null;
        if (kind !== null && !this.cacheUse.kinds.includes(kind)) this.cacheUse.kinds.push(kind);
        if (this.replay(f.slice(0))) read++;
      }
      this.cacheUse.replayed = read;
      // A frame that cannot be read is not offered: the server then sends them all, and they replace what was drawn.
      return read === entry.frames.length ? entry : null;
    });
    this.connect();
  }

  connect() {
    const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
    const url = `${proto}//${location.host}/ws?${LINK_QUERY}`;
    // The first time, the socket index.html opened while the code loaded, if it is this link and
    // not already closing (the server says nothing before hello, so nothing was missed).
    const early = this.adopted ? null : window.vsculptEarlyLink;
    this.adopted = true;
    const adopt = early && early.url === url && early.ws.readyState <= WebSocket.OPEN;
    if (early && !adopt) early.ws.close();
    const ws = adopt ? early.ws : new WebSocket(url);
    let received = 0;
    const stream = new DragStream();
    const meshes = new MeshDeltas();
    /** This connection's mesh frames and deltas (for tools and tests). */
    this.meshes = meshes;
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    this.onStatus('connecting', 'connecting to the server…');
    const first = this.connections++ === 0;
    const hello = async () => {
      // The first hello offers the frames drawn from the cache; a reconnect joins afresh.
      const kept = first ? await this.cached : null;
      if (ws.readyState !== WebSocket.OPEN) return;
      this.cacheUse.offered = kept ? kept.hash : null;
      ws.send(JSON.stringify({
        type: 'hello',
        protocol: PROTOCOL_VERSION,
        token: this.token,
        design: this.design,
        client_name: this.name,
        client_kind: 'browser',
        // The compact join: the shape first, in binary, then a snapshot without points.
        geometry_first: true,
        ...(kept ? { cached_geometry: kept.hash } : {}),
      }));
      this.onHello();
    };
    if (ws.readyState === WebSocket.OPEN) hello();
    else ws.onopen = hello;
    // The join's frames (between a welcome that names them and the snapshot), kept for the next visit.
    let joinFrames = null;
    const text = (data) => {
      let msg;
      try {
        msg = JSON.parse(data);
      } catch (e) {
        this.onStatus('error', `unreadable message from the server: ${e}`);
        return;
      }
      if (msg.type === 'welcome') {
        if (this.cacheUse.offered && this.cacheUse.confirmed === null) this.cacheUse.confirmed = !!msg.geometry_cached;
        joinFrames = this.cache && msg.geometry && !msg.geometry_cached ? { hash: msg.geometry, frames: [] } : null;
        this.backoff = 250;
        this.onStatus('connected', `connected as ${msg.access}`);
      }
      if (msg.type === 'error' && REFUSALS[msg.code] && !this.welcomed) {
        this.closedByServer = true;
        this.refusal = msg.code;
      }
      if (msg.type === 'welcome') this.welcomed = true;
      if (msg.type === 'snapshot' && joinFrames) {
        const kept = joinFrames;
        joinFrames = null;
        this.cacheUse.saved = this.cache.save(this.design, kept.hash, kept.frames).then(() => kept.hash);
      }
      this.onMessage(msg);
    };
    /** Takes one binary frame in; false when it could not be read. */
    const binary = (buf) => {
      // A copy: decoding may hand the frame's buffer on (to the tessellation worker).
      if (joinFrames) joinFrames.frames.push(buf.slice(0));
      try {
        const f = meshes.take(stream.take(decodeFrame(buf)));
        if (f) this.onFrame(f);
        return true;
      } catch (e) {
        this.onStatus('error', `bad geometry frame: ${e.message}`);
        return false;
      }
    };
    /** Draws a frame kept from an earlier visit, as if this connection had received it. */
    this.replay = binary;
    // A deflated message (deflate=1) inflates asynchronously: it and every
    // message after it wait in `inbox`, so all are handled in the order
    // they came.
    let inbox = null;
    // pace=1: report each binary message once it is taken in (inflated and
    // decoded), so a page that cannot keep up is paced like a slow link.
    const taken = (data) => {
      received += data.byteLength;
      if (ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify({ type: 'received', bytes: received }));
    };
    const receive = async (data) => {
      if (typeof data === 'string') return text(data);
      if (!isDeflated(data)) {
        binary(data);
        taken(data);
        return;
      }
      let inner;
      try {
        inner = await inflateMessage(data, PROTOCOL_VERSION);
      } catch (e) {
        this.onStatus('error', `bad geometry frame: ${e.message}`);
        taken(data);
        return;
      }
      binary(inner);
      taken(data);
    };
    ws.onmessage = (ev) => {
      if (!inbox && !isDeflated(ev.data)) {
        receive(ev.data);
        return;
      }
      const p = (inbox || Promise.resolve()).then(() => receive(ev.data));
      inbox = p;
      p.finally(() => {
        if (inbox === p) inbox = null;
      });
    };
    ws.onclose = () => {
      if (this.closedByServer) {
        this.onStatus('error', REFUSALS[this.refusal](this.design));
        return;
      }
      this.welcomed = false;
      this.onStatus('reconnecting', `connection lost; reconnecting in ${Math.round(this.backoff)} ms`);
      setTimeout(() => this.connect(), this.backoff);
      this.backoff = Math.min(this.backoff * 2, 4000);
    };
  }

  /** Sends a message; returns its request number, or null when the link is down and nothing was sent. */
  send(msg) {
    if (!this.open) return null;
    const req = ++this.req;
    this.ws.send(JSON.stringify({ ...msg, req }));
    return req;
  }

  get open() {
    return this.ws && this.ws.readyState === WebSocket.OPEN;
  }
}
