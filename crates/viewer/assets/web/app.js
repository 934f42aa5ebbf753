// The trainee's page: connects to /ws, shows the live state, drives the probe
// with the mouse and keyboard, and runs the exam mode. Protocol: see the
// server's `view/protocol.rs` (JSON envelopes {v, type, ...}; binary frames
// with a 16-byte header "ETHV", version, kind, a, b).
import { ThighScene } from './scene.js';
import { SceneProxy, workerDrawingAvailable } from './scene_proxy.js';
import { EchoView, ForcePlot, Gauge, IMAGING_RATE, drawDepthScale, drawVesselNames, norm, showStatus } from './panels.js';
import { FRAME_IMAGE_JPEG, FRAME_IMAGE_JPEG_FLOW, ImageStream, drawGate } from './image_stream.js';
import { showExam } from './exam.js';
import { deviceDrives, showDevice } from './device.js';
import { Guide } from './guide.js';
import { setupDoppler } from './doppler.js';

const PROTOCOL_VERSION = 2;
const FRAME_IMAGE = 1;
const FRAME_SURFACE = 2;
const FRAME_SURFACE_DELTA = 5; // a changed of b nodes: u32 indices, 3a f32 positions, a f32 compressions
const FRAME_SPECTRAL = 8; // a lines of b rows: u64 first, f64 time, f64 interval, then a·b bytes
const DEPTH_STEP = 0.0005; // m per wheel notch or key press
const MAX_DEPTH = 0.035; // m, below the server's limit
const TILT_STEP = 0.05; // rad
const MAX_TILT = 0.6; // rad, the runtime's limit

const $ = (id) => document.getElementById(id);

// What the page knows, readable by tests and the console.
const live = {
  connected: false, hello: null, state: null, lastError: null, errors: 0,
  exam: null, imageFrames: 0, surfaceFrames: 0, imageTime: null, bytes: 0, largestFrame: 0,
  // Called as fn(kind, performance.now(), detail) on every state ('state',
  // the message) and image ('image', its simulated time): for measurements.
  listeners: [],
  // Arrival times (ms, performance.now) of the last 300 states, images and rendered frames.
  arrivals: { state: [], image: [], render: [] },
  // Where the page's time goes (ms, the last 300 of each): an image from
  // its arrival to its drawing, and one 3D render.
  costs: { image: [], render: [], delivery: [] }, probe: { theta: 0, z: 0, depth: 0.008, tilt: 0, placed: false },
};
window.echothigh = live;
function stamp(list, value = performance.now()) {
  list.push(value);
  if (list.length > 300) list.shift();
}

let scene = null;
function sceneUnavailable(message) {
  $('scene-msg').textContent = `3D view unavailable (WebGL): ${message}`;
  $('scene-msg').classList.remove('hidden');
}
try {
  // Drawn in a worker where the browser can (issue 19: off the page's
  // thread, which handles the states and images), else here.
  scene = workerDrawingAvailable($('scene'))
    ? new SceneProxy($('scene'), sceneUnavailable)
    : new ThighScene($('scene'), window.devicePixelRatio);
} catch (e) {
  sceneUnavailable(e.message);
}
live.scene = scene; // for the browser test and the console
// The image: drawn by a worker on its own socket where the browser can
// (issue 19: off the page's thread; echo_worker.js), else here.
let echoWorker = null;
let echo = null; // the EchoView here, or what the page knows of the worker's
let imageStream = null;
const pixelRequests = new Map();
try {
  if (typeof Worker === 'function' && typeof OffscreenCanvas === 'function' && $('echo').transferControlToOffscreen) {
    const off = $('echo').transferControlToOffscreen();
    echoWorker = new Worker('./echo_worker.js', { type: 'module' });
    echoWorker.onmessage = onEchoWorker;
    echoWorker.postMessage({ type: 'init', canvas: off }, [off]);
    echo = { frames: 0, coloured: 0, width: 0, height: 0 };
  }
} catch (e) {
  echoWorker = null;
}
if (!echoWorker) {
  echo = new EchoView($('echo'));
  imageStream = new ImageStream(echo, {
    ack: () => send({ type: 'image_ack' }),
    decorate: decorateEcho,
    palette: () => doppler.palette(),
    shown: (s) => { stamp(live.costs.image, s.drawn - s.arrived); imageShown(s.time); },
    failed: (message) => toast(message),
  });
}
live.echo = echo;
/** What the image worker says: an image drawn, bytes received, an acknowledgement to pass on. */
function onEchoWorker(e) {
  const m = e.data;
  if (m.type === 'shown') {
    // Its times are epoch ms: on this page's clock, the image is on screen
    // when the worker drew it, whatever this thread was doing.
    const drawn = m.drawn - performance.timeOrigin;
    echo.frames += 1; echo.coloured = m.coloured; echo.width = m.width; echo.height = m.height;
    stamp(live.costs.image, m.drawn - m.arrived);
    imageShown(m.time, drawn);
  } else if (m.type === 'bytes') {
    frameBytes(m.bytes);
  } else if (m.type === 'ack') {
    send({ type: 'image_ack' });
  } else if (m.type === 'open') {
    live.imageSocket = true;
  } else if (m.type === 'closed') {
    live.imageSocket = false;
  } else if (m.type === 'pixels') {
    const done = pixelRequests.get(m.id);
    pixelRequests.delete(m.id);
    if (done) done({ width: m.width, height: m.height, data: m.data });
  } else if (m.type === 'error') {
    toast(m.message);
  }
}
/** The image's pixels as drawn (RGBA), for the browser test: read where it is drawn. */
live.echoPixels = () => {
  if (!echoWorker) {
    const c = $('echo');
    return Promise.resolve({ width: c.width, height: c.height, data: c.getContext('2d').getImageData(0, 0, c.width, c.height).data });
  }
  const id = Math.random();
  return new Promise((resolve) => { pixelRequests.set(id, resolve); echoWorker.postMessage({ type: 'pixels', id }); });
};
const plot = new ForcePlot($('plot'), 5);
const gauge = new Gauge($('gauge-box'));
// The technical status and settings, hidden until asked for (remembered).
function showTech(on) {
  document.body.classList.toggle('tech-on', on);
  $('tech-open').setAttribute('aria-pressed', String(on));
  try { localStorage.setItem('echothigh.tech', on ? '1' : '0'); } catch { /* not remembered */ }
}
$('tech-open').addEventListener('click', () => showTech(!document.body.classList.contains('tech-on')));
showTech((() => { try { return localStorage.getItem('echothigh.tech') === '1'; } catch { return false; } })());
const guide = new Guide($('guide'), document.querySelector('#view3d .help'), $('guide-open'));
const doppler = setupDoppler($, (msg) => send(msg));
live.doppler = doppler; // for the browser test and the console

// ---- connection -----------------------------------------------------------
let ws = null;
function connect() {
  ws = new WebSocket(`${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`);
  ws.binaryType = 'arraybuffer';
  ws.onopen = () => { live.connected = true; setConn(true); imageBox = null; sendImageBox(); };
  ws.onclose = () => { live.connected = false; setConn(false); setTimeout(connect, 1000); };
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') { live.bytes += ev.data.length; onJson(ev.data); }
    else { frameBytes(ev.data.byteLength); onFrame(ev.data); }
  };
}
/** Counts a binary frame's bytes (either socket): the total and the largest. */
function frameBytes(n) {
  live.bytes += n;
  live.largestFrame = Math.max(live.largestFrame, n);
}
function notify(kind, detail, now = performance.now()) {
  for (const f of live.listeners) f(kind, now, detail);
}
function setConn(on) {
  $('conn').textContent = on ? 'live' : 'disconnected — retrying';
  $('conn').className = `conn ${on ? 'on' : 'off'}`;
}
function send(msg) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(msg));
}
live.send = send;

// The box the image is drawn in, in device pixels (issue 19): the server
// sends each frame reduced to fit it, as a scanner scan-converts to its
// monitor (a 1280 × 800 page shows ~230 × 350 of the 512 × 864 rendered).
let imageBox = null;
function sendImageBox() {
  const r = $('echo').getBoundingClientRect();
  const dpr = window.devicePixelRatio || 1;
  const side = (x) => Math.min(8192, Math.max(16, Math.round(x * dpr)));
  const box = [side(r.width), side(r.height)];
  if (imageBox && imageBox[0] === box[0] && imageBox[1] === box[1]) return;
  if (ws && ws.readyState === WebSocket.OPEN) {
    imageBox = box;
    send({ type: 'image_size', width: box[0], height: box[1] });
  }
}
new ResizeObserver(sendImageBox).observe($('echo'));

function onJson(text) {
  const msg = JSON.parse(text);
  if (msg.v !== PROTOCOL_VERSION) return toast(`server speaks protocol v${msg.v}, page v${PROTOCOL_VERSION}`);
  if (msg.type === 'hello') {
    live.hello = msg;
    if (scene) scene.setMesh(msg.mesh);
    // The image socket of this connection, for the worker that draws it.
    if (echoWorker && msg.image_link) {
      const base = `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}`;
      echoWorker.postMessage({ type: 'connect', url: `${base}/ws/image?token=${msg.image_link}` });
    }
  } else if (msg.type === 'state') {
    onState(msg);
  } else if (msg.type === 'error') {
    live.lastError = msg.message;
    live.errors += 1;
    toast(msg.message);
  }
}

function onFrame(buf) {
  const head = new DataView(buf, 0, 16);
  const magic = String.fromCharCode(...new Uint8Array(buf, 0, 4));
  if (magic !== 'ETHV' || head.getUint8(4) !== PROTOCOL_VERSION) return;
  const kind = head.getUint8(5), a = head.getUint32(8, true), b = head.getUint32(12, true);
  if (kind === FRAME_IMAGE && buf.byteLength === 16 + a * b) {
    // Raw frames (not sent by this server, kept by the protocol): drawn
    // here when the page draws its image itself.
    if (!echoWorker) showImage(a, b, new Uint8Array(buf.slice(16)), null);
  } else if (kind === FRAME_SURFACE && buf.byteLength === 16 + 16 * a) {
    surface.pos = new Float32Array(buf.slice(16, 16 + 12 * a));
    surface.comp = new Float32Array(buf.slice(16 + 12 * a));
    showSurface();
  } else if (kind === FRAME_SURFACE_DELTA && buf.byteLength === 16 + 20 * a && a <= b) {
    if (!surface.pos || surface.comp.length !== b) {
      surface.pos = new Float32Array(3 * b); surface.comp = new Float32Array(b);
    }
    const idx = new Uint32Array(buf.slice(16, 16 + 4 * a));
    const pos = new Float32Array(buf.slice(16 + 4 * a, 16 + 16 * a));
    const comp = new Float32Array(buf.slice(16 + 16 * a));
    for (let j = 0; j < a; j++) {
      const i = idx[j];
      surface.pos[3 * i] = pos[3 * j]; surface.pos[3 * i + 1] = pos[3 * j + 1]; surface.pos[3 * i + 2] = pos[3 * j + 2];
      surface.comp[i] = comp[j];
    }
    showSurface();
  } else if (kind === FRAME_SPECTRAL && buf.byteLength === 40 + a * b && b === 64) {
    const interval = new DataView(buf, 32, 8).getFloat64(0, true);
    doppler.lines(new Uint8Array(buf, 40), a, interval);
  } else if (kind === FRAME_IMAGE_JPEG || kind === FRAME_IMAGE_JPEG_FLOW) {
    // On this socket while the worker has none (its first moments, a
    // reconnection): drawn by the worker all the same.
    if (echoWorker) echoWorker.postMessage({ type: 'frame', buf }, [buf]);
    else imageStream.frame(buf);
  }
}

// The surface and the image as the page holds them (the wire sends changes).
const surface = { pos: null, comp: null };
function showSurface() {
  if (scene) scene.updateSurface(surface.pos, surface.comp);
  live.surfaceFrames += 1;
}
/**
 * Over the image: the depth scale (cm), then the Doppler gate. The depth is
 * the drawn section's (it follows the level on a patient's leg), else the
 * hello's field of view.
 */
function imageDepth() {
  const sec = live.state && live.state.section;
  if (sec && sec.image_depth > 0) return sec.image_depth;
  return live.hello && live.hello.image ? live.hello.image.depth : 0;
}
/** Whether the vessels are named on the image: asked for, and no exam case open. */
function hintOn() {
  const e = live.state && live.state.exam;
  return $('hint').checked && !(e && e.open);
}
/**
 * What is drawn over the image, from the newest state: the depth (m), the
 * vessels' labels when the hint is on (else null), the image's width (m),
 * the PW gate in spectral mode (else null).
 */
function imageDecor() {
  const s = live.state;
  const sec = s && s.section;
  const d = s && s.doppler;
  return {
    depth: imageDepth(),
    labels: sec && hintOn() ? sec.labels : null,
    width: live.hello && live.hello.image ? live.hello.image.width : 0,
    gate: d && d.mode === 'spectral' ? { x: d.gate.x, y: d.gate.y } : null,
  };
}
function decorateEcho(ctx, w, h) {
  const d = imageDecor();
  drawDepthScale(ctx, w, h, d.depth);
  if (d.labels) drawVesselNames(ctx, w, h, d.labels, d.width, d.depth);
  drawGate(ctx, w, h, d.gate);
}
/** Sends the worker the decorations (and the overlay's palette) when they change. */
const sentDecor = { key: '', palette: null };
function postDecor() {
  if (!echoWorker) return;
  const decor = imageDecor();
  const key = JSON.stringify(decor);
  const palette = doppler.palette();
  if (key === sentDecor.key && palette === sentDecor.palette) return;
  echoWorker.postMessage({ type: 'decor', decor, palette: palette === sentDecor.palette ? null : palette });
  sentDecor.key = key; sentDecor.palette = palette;
}
$('hint').addEventListener('change', postDecor);
function showImage(w, h, px, time) {
  echo.draw(w, h, px, null, null, decorateEcho);
  imageShown(time);
}
function imageShown(time, at = performance.now()) {
  live.imageFrames += 1;
  live.imageTime = time;
  stamp(live.arrivals.image, at);
  notify('image', time, at);
}
// ---- state ---------------------------------------------------------------
let renderedFps = 0;
function onState(s) {
  // The exam status comes only when it changed: keep the last one.
  if (s.exam) live.exam = s.exam; else s.exam = live.exam;
  live.state = s;
  // Flow control: the server sends the next state once this one is taken.
  send({ type: 'ack', seq: s.seq });
  stamp(live.arrivals.state);
  // How long the state took from the server to this handler (ms; one
  // machine's clock, or two in step).
  if (s.sent_ms > 0) stamp(live.costs.delivery, performance.timeOrigin + performance.now() - s.sent_ms);
  notify('state', s);
  const rendered = norm(s.rendered_force), physics = norm(s.physics_force);
  plot.push(s.time, rendered, physics);
  gauge.update(rendered, physics, s.max_force, s.section && s.section.target_band);
  if (scene) scene.updateState(s);
  postDecor();
  // The panels (text the trainee reads) follow at most every PANELS_MS,
  // with the newest state: at 40 states/s their DOM updates (style,
  // layout, paint) held the page's thread from the next state (issue 19).
  // A change the trainee acts on (the exam, the vein, who drives, a fault,
  // the mode) shows at once.
  const now = performance.now();
  const key = `${s.vein}|${s.observer}|${s.fault}|${s.mode}|${s.exam_playing}|${s.doppler && s.doppler.mode}|${!!s.haptic_device}`;
  const changed = key !== panels.key || s.exam !== panels.exam;
  panels.key = key; panels.exam = s.exam;
  if (changed || now - panels.at >= PANELS_MS) showPanels(s);
  else if (!panels.timer) panels.timer = setTimeout(() => showPanels(live.state), PANELS_MS - (now - panels.at));
}
const PANELS_MS = 200;
const panels = { at: -Infinity, timer: null, key: '', exam: null };
function showPanels(s) {
  panels.at = performance.now();
  if (panels.timer) { clearTimeout(panels.timer); panels.timer = null; }
  showStatus(s, renderedFps);
  syncControls(s);
  showExam(s.exam, s.level_s, send);
  showDevice(s, scene);
  guide.update(s, live.probe, deviceDrives(s));
  doppler.update(s.doppler);
  $('observer').hidden = !s.observer;
  $('hint').disabled = !!(s.exam && s.exam.open);
  showBehind(s);
}

/** Says so when the simulation runs slower than set (achieved rates). */
function showBehind(s) {
  const late = [];
  // Haptics: the device loop runs at 1 kHz; below 900 Hz the feel degrades.
  if (s.haptic_rate > 0 && s.haptic_rate < 900) late.push(`touch feedback at ${s.haptic_rate.toFixed(0)} Hz of 1000`);
  // Physics: below 80 % of its setting the buffer model ages visibly.
  if (s.physics_rate > 0 && s.physics_rate < 0.8 * s.physics_rate_setting && s.mode !== 'direct') {
    late.push(`tissue simulation at ${s.physics_rate.toFixed(0)} Hz of ${s.physics_rate_setting.toFixed(0)}`);
  }
  // The image: below half its schedule the probe's effect shows late.
  if (s.imaging_rate > 0 && s.imaging_rate < 0.5 * IMAGING_RATE) {
    late.push(`ultrasound image at ${s.imaging_rate.toFixed(0)} frames/s of ${IMAGING_RATE}`);
  }
  $('behind').hidden = late.length === 0;
  $('behind').textContent = late.length ? `The computer is falling behind: ${late.join(', ')}.` : '';
}

function syncControls(s) {
  const idle = (el) => document.activeElement !== el;
  if (!s.vein) $('vein').value = ''; // hidden during an exam question
  else if (idle($('vein'))) $('vein').value = s.vein;
  $('vein').disabled = !s.vein;
  if (s.mode && idle($('mode'))) $('mode').value = s.mode;
  if (idle($('rate'))) { $('rate').value = s.physics_rate_setting; $('rate-v').textContent = s.physics_rate_setting.toFixed(0); }
  if (idle($('latency'))) {
    $('latency').value = s.latency_setting * 1000;
    $('latency-v').textContent = (s.latency_setting * 1000).toFixed(0);
  }
  $('play').textContent = s.exam_playing ? 'Stop scripted exam' : 'Play scripted exam';
}

let toastTimer = null;
function toast(text) {
  $('toast').textContent = text;
  $('toast').classList.remove('hidden');
  clearTimeout(toastTimer);
  toastTimer = setTimeout(() => $('toast').classList.add('hidden'), 4000);
}
// A click dismisses the message at once.
$('toast').addEventListener('click', () => $('toast').classList.add('hidden'));

// ---- probe driving -------------------------------------------------------
let probeDirty = false;
function sendProbeSoon() { probeDirty = true; }
function flushProbe() {
  // A haptic device drives the probe: the page only watches (issue 15).
  if (!probeDirty || !live.probe.placed || deviceDrives(live.state)) return;
  probeDirty = false;
  const p = live.probe;
  send({ type: 'probe', theta: p.theta, z: p.z, depth: p.depth, tilt: p.tilt });
}
function setDepth(d) {
  live.probe.depth = Math.min(Math.max(d, 0), MAX_DEPTH);
  $('depth').textContent = (live.probe.depth * 1000).toFixed(1);
  sendProbeSoon();
}
function setTilt(t) {
  live.probe.tilt = Math.min(Math.max(t, -MAX_TILT), MAX_TILT);
  $('tilt').textContent = ((live.probe.tilt * 180) / Math.PI).toFixed(0);
  sendProbeSoon();
}
function lift() {
  if (deviceDrives(live.state)) return;
  live.probe.placed = false;
  send({ type: 'lift' });
}

const canvas = $('scene');
let drag = null; // {mode: 'probe' | 'orbit', x, y}
canvas.addEventListener('contextmenu', (e) => e.preventDefault());
canvas.addEventListener('pointerdown', (e) => {
  canvas.setPointerCapture(e.pointerId);
  const hit = scene && e.button === 0 && !deviceDrives(live.state) ? scene.pick(e.clientX, e.clientY) : null;
  if (hit) {
    if (live.state && live.state.exam_playing) send({ type: 'stop_exam' });
    Object.assign(live.probe, hit, { placed: true });
    sendProbeSoon();
  }
  drag = { mode: hit ? 'probe' : 'orbit', x: e.clientX, y: e.clientY };
});
canvas.addEventListener('pointermove', (e) => {
  if (!drag || !scene) return;
  if (drag.mode === 'probe') {
    const hit = scene.pick(e.clientX, e.clientY);
    if (hit) { Object.assign(live.probe, hit); sendProbeSoon(); }
  } else {
    scene.rotate(e.clientX - drag.x, e.clientY - drag.y);
  }
  drag.x = e.clientX; drag.y = e.clientY;
});
canvas.addEventListener('pointerup', () => { drag = null; });
canvas.addEventListener('wheel', (e) => {
  e.preventDefault();
  if (e.shiftKey) { if (scene) scene.zoom(e.deltaY > 0 ? 1.1 : 1 / 1.1); return; }
  setDepth(live.probe.depth + (e.deltaY < 0 ? DEPTH_STEP : -DEPTH_STEP));
}, { passive: false });
// Shortcuts act on the probe only while the 3D view has focus, never on a
// focused control (issue 19: ↑ on the vein menu switched it to acute).
const THETA_STEP = 0.05; // rad around the thigh per arrow press
const Z_STEP = 0.005; // m along the thigh per arrow press
function moveProbe(dTheta, dZ) {
  const p = live.probe;
  p.theta = Math.max(-Math.PI, Math.min(Math.PI, p.theta + dTheta));
  const half = live.hello ? halfLength(live.hello.mesh) : 0.1;
  p.z = Math.max(-half, Math.min(half, p.z + dZ));
  if (p.placed) sendProbeSoon();
}
function halfLength(mesh) {
  let m = 0;
  for (const r of mesh.rest) m = Math.max(m, Math.abs(r[2]));
  return 0.9 * m;
}
canvas.addEventListener('keydown', (e) => {
  const k = e.key.toLowerCase();
  if (k === 'arrowleft') moveProbe(-THETA_STEP, 0);
  else if (k === 'arrowright') moveProbe(THETA_STEP, 0);
  else if (k === 'arrowup') moveProbe(0, Z_STEP);
  else if (k === 'arrowdown') moveProbe(0, -Z_STEP);
  else if (k === 'enter') {
    if (live.state && live.state.exam_playing) send({ type: 'stop_exam' });
    live.probe.placed = true; sendProbeSoon();
  } else if (k === 'w') setDepth(live.probe.depth + DEPTH_STEP);
  else if (k === 's') setDepth(live.probe.depth - DEPTH_STEP);
  else if (k === 'q') setTilt(live.probe.tilt - TILT_STEP);
  else if (k === 'e') setTilt(live.probe.tilt + TILT_STEP);
  else if (k === 'l') lift();
  else return;
  e.preventDefault();
});

// ---- controls ------------------------------------------------------------
$('vein').addEventListener('change', (e) => send({ type: 'set_vein', vein: e.target.value }));
$('mode').addEventListener('change', (e) => send({ type: 'set_mode', mode: e.target.value }));
$('rate').addEventListener('input', (e) => { $('rate-v').textContent = e.target.value; });
$('rate').addEventListener('change', (e) => send({ type: 'set_physics_rate', hz: Number(e.target.value) }));
$('latency').addEventListener('input', (e) => { $('latency-v').textContent = e.target.value; });
$('latency').addEventListener('change', (e) => send({ type: 'set_latency', seconds: Number(e.target.value) / 1000 }));
$('lift').addEventListener('click', lift);
$('reset').addEventListener('click', () => { live.probe.placed = false; send({ type: 'reset' }); });
$('play').addEventListener('click', () => {
  live.probe.placed = false;
  send({ type: live.state && live.state.exam_playing ? 'stop_exam' : 'play_exam' });
});
$('exam-start').addEventListener('click', () => { live.probe.placed = false; send({ type: 'exam_start' }); });
$('exam-finish').addEventListener('click', () => send({ type: 'exam_finish' }));
$('exam-stop').addEventListener('click', () => send({ type: 'exam_stop' }));
$('take-control').addEventListener('click', () => send({ type: 'take_control' }));

// ---- frame loop ----------------------------------------------------------
// The 3D view's rate counts the frames drawn (by the worker or here), not
// the page's animation frames, most of which draw nothing.
let renders = 0;
let fpsWindow = { t: performance.now(), renders: 0, echo: 0 };
// The leg is drawn when something changed, and at least every
// REDRAW_MS (a change the page did not flag, e.g. a resize). When the
// animation frames come slowly (the smoothed interval above SLOW_MS: a
// software-rendered page on a busy machine), the 3D view's resolution is
// lowered in steps (to half at most), and raised again once frames come
// quickly (below FAST_MS), at most one step a second, so that drawing the
// leg leaves the page free to take the states as they come (issue 19's
// lag) and the simulation its cores.
const REDRAW_MS = 500, SLOW_MS = 60, FAST_MS = 30;
const adapt = { last: performance.now(), smooth: 16, changed: performance.now(), drawn: 0, rendered: false, seen: 0 };
/** Smooths the intervals that follow a drawn frame (what drawing costs) and steps the scale. */
function adaptScale(now) {
  const dt = now - adapt.last;
  adapt.last = now;
  if (scene instanceof SceneProxy) return adaptWorkerScale(now);
  if (adapt.rendered) adapt.smooth += 0.1 * (Math.min(dt, 1000) - adapt.smooth);
  adapt.rendered = false;
  if (!scene || now - adapt.changed < 1000) return;
  if (adapt.smooth > SLOW_MS && scene.scale > 0.5) { scene.setScale(scene.scale * 0.8); adapt.changed = now; }
  else if (adapt.smooth < FAST_MS && scene.scale < 1) { scene.setScale(scene.scale / 0.8); adapt.changed = now; }
}
/**
 * The scale of a view drawn in a worker follows its render's own cost (the
 * page's frame intervals no longer show it), smoothed as above; on a
 * software rasterizer it stays at half (its pixels are drawn on the cores
 * the simulation runs on).
 */
function adaptWorkerScale(now) {
  const costs = scene.costs;
  const fresh = Math.min(scene.frames - adapt.seen, costs.length);
  for (const c of costs.slice(costs.length - fresh)) adapt.smooth += 0.1 * (Math.min(c, 1000) - adapt.smooth);
  adapt.seen = scene.frames;
  if (now - adapt.changed < 1000) return;
  const top = scene.software ? 0.5 : 1;
  if (adapt.smooth > SLOW_MS && scene.scale > 0.5) { scene.setScale(scene.scale * 0.8); adapt.changed = now; }
  else if (adapt.smooth < FAST_MS && scene.scale < top) { scene.setScale(Math.min(scene.scale / 0.8, top)); adapt.changed = now; }
}
/** A frame the worker drew: its cost and arrival for the page's figures. */
function workerRendered(cost) {
  renders += 1;
  stamp(live.arrivals.render);
  stamp(live.costs.render, cost);
}
if (scene instanceof SceneProxy) scene.onRendered = workerRendered;
// On a software rasterizer a 3D frame holds the page's thread until the
// rasterizer has drawn it (the compositor reads it back): at most one every
// SOFTWARE_MIN_MS there, so that the states are taken as they come.
const SOFTWARE_MIN_MS = 125;
function frame(now) {
  flushProbe();
  adaptScale(now);
  const due = !scene || !scene.software || now - adapt.drawn >= SOFTWARE_MIN_MS;
  if (scene && due && (scene.dirty || now - adapt.drawn > REDRAW_MS)) {
    const t = performance.now();
    scene.render(); adapt.drawn = now;
    // A worker's frame is counted when it reports it drawn (workerRendered).
    if (!(scene instanceof SceneProxy)) {
      renders += 1;
      adapt.rendered = true; stamp(live.arrivals.render);
      stamp(live.costs.render, performance.now() - t);
    }
  }
  if (plot.dirty) plot.draw();
  if (now - fpsWindow.t >= 1000) {
    const dt = (now - fpsWindow.t) / 1000;
    renderedFps = (renders - fpsWindow.renders) / dt;
    $('echo-fps').textContent = `${((echo.frames - fpsWindow.echo) / dt).toFixed(0)} frames/s`;
    fpsWindow = { t: now, renders, echo: echo.frames };
  }
  requestAnimationFrame(frame);
}
setDepth(live.probe.depth);
probeDirty = false;
connect();
requestAnimationFrame(frame);
