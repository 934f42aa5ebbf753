// The image frames (issue 19), as the page's worker (echo_worker.js) or, where
// no worker can draw, the page itself receives them: each JPEG frame (kinds 3
// and 6 of the server's `protocol.rs`) decoded and drawn with its
// decorations, with the wire's flow control (one image decoding and one
// more on its way: the first is acknowledged on arrival, so the server
// renders and sends the next while it decodes; one that arrives while
// another decodes is acknowledged when that one is drawn).

export const FRAME_IMAGE_JPEG = 3; // f64 time, then a gray JPEG
export const FRAME_IMAGE_JPEG_FLOW = 6; // as 3, with u32 length L before the JPEG, then the colour overlay's PNG
const PROTOCOL_VERSION = 2;

/** Draws the PW sample gate on the image (`gate`: x, y in 0..1 of the image), as a scanner does. */
export function drawGate(ctx, w, h, gate) {
  if (!gate) return;
  const x = gate.x * w, y = gate.y * h;
  ctx.save();
  ctx.strokeStyle = '#ffe066'; ctx.lineWidth = 1;
  ctx.beginPath(); ctx.moveTo(x, 0); ctx.lineTo(x, y - 6); ctx.stroke();
  ctx.strokeRect(x - 5, y - 4, 10, 8);
  ctx.restore();
}

/**
 * The image stream into an `EchoView` (panels.js). `hooks`: `ack()` sends
 * `image_ack`; `decorate(ctx, w, h)` draws over each image; `palette()`
 * gives the colour overlay's 256 RGB triples; `shown({time, arrived,
 * drawn, bytes, width, height})` (ms on `performance.now`) follows each
 * drawn image; `failed(message)` an image that could not be drawn.
 */
export class ImageStream {
  constructor(view, hooks) {
    this.view = view;
    this.hooks = hooks;
    this.decoding = 0; // images received and not yet drawn
    this.ackOwed = false; // an image_ack held back while one decodes
    this.chain = Promise.resolve();
    this.gray = new OffscreenCanvas(1, 1);
    this.grayCtx = this.gray.getContext('2d', { willReadFrequently: true });
    this.last = null; // the newest frame drawn, to draw again with new decorations
  }

  /** Takes a binary frame; false if it is not an image frame. */
  frame(buf) {
    if (buf.byteLength < 16) return false;
    const head = new DataView(buf, 0, 16);
    const magic = String.fromCharCode(...new Uint8Array(buf, 0, 4));
    if (magic !== 'ETHV' || head.getUint8(4) !== PROTOCOL_VERSION) return false;
    const kind = head.getUint8(5), a = head.getUint32(8, true), b = head.getUint32(12, true);
    const flow = kind === FRAME_IMAGE_JPEG_FLOW;
    if (!(kind === FRAME_IMAGE_JPEG && buf.byteLength > 24 || flow && buf.byteLength > 28)) return false;
    const time = new DataView(buf, 16, 8).getFloat64(0, true);
    const len = flow ? new DataView(buf, 24, 4).getUint32(0, true) : buf.byteLength - 24;
    const at = flow ? 28 : 24;
    if (at + len > buf.byteLength) return false;
    const jpeg = new Blob([new Uint8Array(buf, at, len)], { type: 'image/jpeg' });
    const codes = flow ? new Blob([new Uint8Array(buf, at + len)], { type: 'image/png' }) : null;
    const arrived = performance.now();
    this.decoding += 1;
    if (this.decoding === 1) this.hooks.ack(); else this.ackOwed = true;
    // A B-mode frame is drawn as decoded; with the flow's codes, its
    // pixels are read back to be coloured.
    const decoded = flow
      ? () => Promise.all([this.decodeGray(jpeg, a, b), this.decodeGray(codes, a, b)])
        .then(([px, overlay]) => ({ a, b, px, overlay }))
      : () => this.decodeBitmap(jpeg, a, b).then((bmp) => ({ a, b, bmp }));
    this.chain = this.chain.then(decoded).then((f) => {
      this.keep(f);
      this.draw();
      this.hooks.shown({ time, arrived, drawn: performance.now(), bytes: buf.byteLength, width: a, height: b });
    }).catch((e) => this.hooks.failed(`image: ${e.message}`))
      .finally(() => {
        this.decoding -= 1;
        if (this.ackOwed) { this.ackOwed = false; this.hooks.ack(); }
      });
    return true;
  }

  /** Keeps `f` as the newest frame (the previous bitmap released). */
  keep(f) {
    if (this.last && this.last.bmp) this.last.bmp.close();
    this.last = f;
  }

  /** Draws the newest frame with the current decorations. */
  draw() {
    const f = this.last;
    if (!f) return;
    const decorate = this.hooks.decorate;
    if (f.bmp) this.view.drawBitmap(f.bmp, decorate);
    else this.view.draw(f.a, f.b, f.px, f.overlay, this.hooks.palette(), decorate);
  }

  /** An 8-bit gray JPEG or PNG decoded as it is (no colour management), checked against its header's size. */
  async decodeBitmap(blob, w, h) {
    const bmp = await createImageBitmap(blob, { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
    if (bmp.width !== w || bmp.height !== h) {
      bmp.close();
      throw new Error(`image of ${bmp.width}×${bmp.height}, header ${w}×${h}`);
    }
    return bmp;
  }

  /** The gray levels of an 8-bit gray JPEG or PNG (no colour management). */
  async decodeGray(blob, w, h) {
    const bmp = await this.decodeBitmap(blob, w, h);
    this.gray.width = w; this.gray.height = h;
    this.grayCtx.drawImage(bmp, 0, 0);
    bmp.close();
    const rgba = this.grayCtx.getImageData(0, 0, w, h).data;
    const px = new Uint8Array(w * h);
    for (let i = 0, j = 0; i < px.length; i++, j += 4) px[i] = rgba[j];
    return px;
  }
}
