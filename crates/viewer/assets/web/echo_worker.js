// The echographic image drawn off the page's thread (issue 19): this worker
// owns the image canvas (an OffscreenCanvas) and its own WebSocket, the
// image socket of the page's connection (`/ws/image?token=…`, the server's
// `image_link.rs`), so that an image goes from the server to the screen
// without waiting for the page's thread (a slow page keeps it busy with its
// layout and paint: in the browser test an image waited 20 ms p50 / 43 ms
// p95 for the page's handler and 34 / 103 ms more to be drawn).
// The page (app.js) sends the canvas, the socket's address, and the
// decorations (depth scale, vessel names, PW gate, overlay palette) as its
// states change; this worker tells it each image drawn.
import { EchoView, drawDepthScale, drawVesselNames } from './panels.js';
import { ImageStream, drawGate } from './image_stream.js';

let stream = null;
let ws = null;
let url = null;
// What is drawn over the image: the depth (m), the vessels' labels (or
// null), the image's width (m), the PW gate (or null); the overlay palette.
let decor = { depth: 0, labels: null, width: 0, gate: null };
let palette = null;

/** Epoch ms (the page converts it to its own clock). */
const epoch = (t) => performance.timeOrigin + t;

function connect(to) {
  url = to;
  if (ws) { ws.onclose = null; ws.close(); }
  ws = new WebSocket(url);
  ws.binaryType = 'arraybuffer';
  ws.onopen = () => self.postMessage({ type: 'open' });
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') return;
    // The page counts the bytes of both sockets (its budget, issue 19).
    self.postMessage({ type: 'bytes', bytes: ev.data.byteLength });
    stream.frame(ev.data);
  };
  // The page's connection offers a new token when it reconnects: the
  // worker waits for it (a token is good once), and the server sends the
  // images on the page's socket meanwhile.
  ws.onclose = () => { ws = null; self.postMessage({ type: 'closed' }); };
}

self.onmessage = (e) => {
  const m = e.data;
  if (m.type === 'init') {
    stream = new ImageStream(new EchoView(m.canvas), {
      // Either socket's acknowledgement frees the connection's next image.
      ack: () => {
        if (ws && ws.readyState === WebSocket.OPEN) ws.send('{"type":"image_ack"}');
        else self.postMessage({ type: 'ack' });
      },
      decorate: (ctx, w, h) => {
        drawDepthScale(ctx, w, h, decor.depth);
        if (decor.labels) drawVesselNames(ctx, w, h, decor.labels, decor.width, decor.depth);
        drawGate(ctx, w, h, decor.gate);
      },
      palette: () => palette,
      shown: (s) => self.postMessage({
        type: 'shown', time: s.time, arrived: epoch(s.arrived), drawn: epoch(s.drawn),
        bytes: s.bytes, width: s.width, height: s.height, coloured: stream.view.coloured,
      }),
      failed: (message) => self.postMessage({ type: 'error', message }),
    });
  } else if (m.type === 'connect') {
    if (m.url !== url || !ws) connect(m.url);
  } else if (m.type === 'frame') {
    // An image that came on the page's socket.
    stream.frame(m.buf);
  } else if (m.type === 'decor') {
    decor = m.decor;
    if (m.palette) palette = m.palette;
    if (stream) stream.draw();
  } else if (m.type === 'pixels') {
    // For the browser test: the canvas as drawn, read in this worker.
    const c = stream.view.canvas;
    const d = stream.view.ctx.getImageData(0, 0, c.width, c.height);
    self.postMessage({ type: 'pixels', id: m.id, width: c.width, height: c.height, data: d.data }, [d.data.buffer]);
  }
};
