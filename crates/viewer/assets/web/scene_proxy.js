// The page's side of the 3D view drawn in a worker (scene_worker.js): the
// same calls as ThighScene, forwarded; the picks, the orbit and the camera
// stay here (a ThighScene without a renderer) so that a drag answers at
// once. Where a worker cannot draw WebGL on an OffscreenCanvas, the page
// uses ThighScene on its own thread (app.js).
import { ThighScene, softwareRenderer } from './scene.js';

/** Whether this browser can draw the view in a worker. */
export function workerDrawingAvailable(canvas) {
  return typeof Worker !== 'undefined' && typeof OffscreenCanvas !== 'undefined' &&
    typeof canvas.transferControlToOffscreen === 'function' &&
    typeof OffscreenCanvas.prototype.getContext === 'function';
}

export class SceneProxy {
  /** `onError(message)`: the worker failed (the view stays as last drawn). */
  constructor(canvas, onError) {
    this.canvas = canvas;
    const ratio = window.devicePixelRatio || 1;
    this.view = new ThighScene(canvas, ratio, false);
    this.software = softwareRenderer();
    this.scale = this.software ? 0.5 : 1;
    this.dirty = true;
    this.frames = 0;
    // The cost of the worker's last renders (ms), for the page's figures.
    this.costs = [];
    this.inFlight = false;
    this.surface = null; // the newest surface not yet sent: [pos, comp]
    this.state = null; // the newest state not yet sent
    this.inkWaiters = [];
    this.onRendered = null; // fn(cost ms), set by the page
    this.worker = new Worker(new URL('./scene_worker.js', import.meta.url), { type: 'module' });
    this.worker.onmessage = (e) => this.onMessage(e.data);
    this.worker.onerror = (e) => onError(e.message || 'the 3D view\'s worker failed');
    this.onError = onError;
    const offscreen = canvas.transferControlToOffscreen();
    this.worker.postMessage({ type: 'init', canvas: offscreen, pixelRatio: ratio }, [offscreen]);
  }

  onMessage(m) {
    if (m.type === 'rendered') {
      this.inFlight = false;
      this.frames += 1;
      this.costs.push(m.cost);
      if (this.costs.length > 300) { this.costs.shift(); }
      if (this.onRendered) this.onRendered(m.cost);
      if (m.ink) for (const w of this.inkWaiters.splice(0)) w(m.ink);
    } else if (m.type === 'ready') {
      this.scale = m.scale;
    } else if (m.type === 'error') {
      this.inFlight = false;
      this.onError(m.message);
    }
  }

  setMesh(mesh) {
    this.view.setMesh(mesh);
    this.worker.postMessage({ type: 'mesh', mesh });
    this.surface = null;
    this.dirty = true;
  }

  /** Keeps the newest surface; it goes with the next frame. */
  updateSurface(positions, compression) {
    this.surface = [positions, compression];
    this.dirty = true;
  }

  /** Keeps the newest state (the fields the view draws); it goes with the next frame. */
  updateState(s) {
    this.view.updateState(s);
    this.state = {
      level: s.level, probe_orientation: s.probe_orientation, probe_position: s.probe_position,
      device: s.device, proxy: s.proxy, rendered_force: s.rendered_force, physics_force: s.physics_force,
    };
    this.dirty = true;
  }

  /** The device's workspace (8 corners, m, or null), sent when it changes. */
  setWorkspace(corners) {
    const key = corners ? JSON.stringify(corners) : '';
    if (key === (this.workspaceKey ?? '')) return;
    this.workspaceKey = key;
    this.worker.postMessage({ type: 'workspace', corners: corners || null });
    this.dirty = true;
  }

  pick(clientX, clientY) { return this.view.pick(clientX, clientY); }

  rotate(dx, dy) { this.view.rotate(dx, dy); this.dirty = true; }

  zoom(factor) { this.view.zoom(factor); this.dirty = true; }

  setScale(scale) {
    const s = Math.min(Math.max(scale, 0.5), 1);
    if (s === this.scale) return;
    this.scale = s;
    this.worker.postMessage({ type: 'scale', scale: s });
    this.dirty = true;
  }

  /**
   * Asks the worker for a frame of the newest surface and state, unless one
   * is still being drawn (frames never queue); `ink`: read its pixels back.
   */
  render(ink = false) {
    if (this.inFlight && !ink) return;
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    if (w === 0 || h === 0) return;
    if (this.surface) {
      // Copies: the page keeps updating its own arrays.
      const [pos, comp] = this.surface.map((a) => a.slice());
      this.worker.postMessage({ type: 'surface', pos, comp }, [pos.buffer, comp.buffer]);
      this.surface = null;
    }
    if (this.state) { this.worker.postMessage({ type: 'state', s: this.state }); this.state = null; }
    const o = this.view.orbit, t = this.view.target;
    this.worker.postMessage({ type: 'render', w, h, ink,
      orbit: { azimuth: o.azimuth, elevation: o.elevation, distance: o.distance }, target: [t.x, t.y, t.z] });
    this.inFlight = true;
    this.dirty = false;
  }

  /** A frame drawn now and its pixels' ink (a promise; the browser test's check). */
  ink() {
    return new Promise((resolve) => { this.inkWaiters.push(resolve); this.render(true); });
  }
}
