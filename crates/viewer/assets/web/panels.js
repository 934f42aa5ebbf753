// The 2D panels: the echographic image, the force gauge, the scrolling force
// plot (rendered vs physics force, paper Fig. 4) and the status table.

/** Euclidean norm of a 3-vector (N). */
export function norm(v) {
  return Math.hypot(v[0], v[1], v[2]);
}

/** Draws 8-bit grayscale frames (row-major, axial rows) on a canvas. */
export class EchoView {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.image = null;
    this.frames = 0;
  }

  /**
   * `pixels`: Uint8Array of width × height; `overlay` (optional, same
   * size): colour codes drawn with `palette` (256 RGB triples) where not 0
   * (issue 17); `decorate(ctx, w, h)` draws over the image (the PW gate).
   */
  draw(width, height, pixels, overlay = null, palette = null, decorate = null) {
    if (width === 0 || height === 0) return;
    if (!this.image || this.image.width !== width || this.image.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
      this.image = this.ctx.createImageData(width, height);
    }
    const rgba = this.image.data;
    for (let i = 0, j = 0; i < pixels.length; i++, j += 4) {
      const g = pixels[i];
      rgba[j] = g; rgba[j + 1] = g; rgba[j + 2] = g; rgba[j + 3] = 255;
    }
    if (overlay && palette && overlay.length === pixels.length) {
      let coloured = 0;
      for (let i = 0, j = 0; i < overlay.length; i++, j += 4) {
        const c = overlay[i];
        if (c) { rgba[j] = palette[3 * c]; rgba[j + 1] = palette[3 * c + 1]; rgba[j + 2] = palette[3 * c + 2]; coloured++; }
      }
      this.coloured = coloured;
    } else this.coloured = 0;
    this.ctx.putImageData(this.image, 0, 0);
    if (decorate) decorate(this.ctx, width, height);
    this.frames += 1;
  }
}

/** The force the trainee would feel, against the device limit. */
export class Gauge {
  constructor(fill, limit, value) {
    this.fill = fill; this.limit = limit; this.value = value;
  }

  /** `force` (N, rendered), `maxForce` (N, device limit in tissue units). */
  update(force, maxForce) {
    const scale = Math.max(maxForce * 1.25, 1);
    const frac = Math.min(force / scale, 1);
    this.fill.style.height = `${(frac * 100).toFixed(1)}%`;
    this.fill.style.background = force > maxForce ? '#c0262b' : force > 0.7 * maxForce ? '#e8a33a' : '#3fd07a';
    this.limit.style.top = `${(100 - (maxForce / scale) * 100).toFixed(1)}%`;
    this.value.textContent = `${force.toFixed(1)} N`;
  }
}

/** |F| of the rendered and the physics force over the last `span` seconds. */
export class ForcePlot {
  constructor(canvas, span = 5) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.span = span;
    this.samples = []; // [t (s), rendered (N), physics (N)]
  }

  push(t, rendered, physics) {
    const last = this.samples[this.samples.length - 1];
    if (last && t < last[0]) this.samples.length = 0; // time went back: a reset
    if (last && t === last[0]) return;
    this.samples.push([t, rendered, physics]);
    while (this.samples.length && this.samples[0][0] < t - this.span) this.samples.shift();
  }

  draw() {
    const { ctx, canvas } = this;
    const w = canvas.width, h = canvas.height, pad = { l: 34, r: 6, t: 6, b: 18 };
    ctx.fillStyle = '#0c0f14';
    ctx.fillRect(0, 0, w, h);
    const end = this.samples.length ? this.samples[this.samples.length - 1][0] : 0;
    let top = 5;
    for (const s of this.samples) top = Math.max(top, s[1], s[2]);
    top = niceCeil(top * 1.1);
    const x = (t) => pad.l + ((t - (end - this.span)) / this.span) * (w - pad.l - pad.r);
    const y = (f) => h - pad.b - (f / top) * (h - pad.t - pad.b);
    ctx.strokeStyle = '#2a313d';
    ctx.fillStyle = '#8d96a5';
    ctx.font = '10px system-ui, sans-serif';
    ctx.lineWidth = 1;
    for (let i = 0; i <= 4; i++) {
      const f = (top * i) / 4;
      ctx.beginPath(); ctx.moveTo(pad.l, y(f)); ctx.lineTo(w - pad.r, y(f)); ctx.stroke();
      ctx.fillText(`${f.toFixed(f < 10 ? 1 : 0)} N`, 2, y(f) + 3);
    }
    for (let s = 0; s <= this.span; s++) ctx.fillText(`-${this.span - s} s`, x(end - this.span + s) - 8, h - 4);
    const line = (k, colour) => {
      ctx.strokeStyle = colour; ctx.lineWidth = 1.5; ctx.beginPath();
      this.samples.forEach((s, i) => (i ? ctx.lineTo(x(s[0]), y(s[k])) : ctx.moveTo(x(s[0]), y(s[k]))));
      ctx.stroke();
    };
    line(2, '#b071ff');
    line(1, '#ff9a1f');
  }
}

/** Smallest of 1, 2, 5 × 10^k not below `v`. */
function niceCeil(v) {
  const p = 10 ** Math.floor(Math.log10(v));
  for (const m of [1, 2, 5, 10]) if (m * p >= v) return m * p;
  return 10 * p;
}

/** Fills the status table from a `state` message. */
/** How a sonographer names the stretch of vein under the probe (runtime's `LegLevel`). */
const LEVEL_NAMES = {
  above_groin: 'above the groin (outside the thigh)',
  common_femoral: 'common femoral vein (groin)',
  saphenofemoral: 'saphenofemoral junction',
  femoral_proximal: 'proximal femoral vein',
  femoral_canal: 'femoral vein, adductor canal (mid-thigh)',
  popliteal: 'popliteal vein (behind the knee)',
  below_knee: 'below the knee (outside the model)',
};

export function showStatus(s, fps) {
  const set = (id, text) => { document.getElementById(id).textContent = text; };
  set('st-physics', `${s.physics_rate.toFixed(0)} Hz (set ${s.physics_rate_setting.toFixed(0)})`);
  set('st-haptic', `${s.haptic_rate.toFixed(0)} Hz`);
  set('st-missed', `${s.missed_deadlines}`);
  set('st-age', `${(s.model_age * 1000).toFixed(1)} ms`);
  set('st-mode', `${s.mode ?? '–'}${s.latency_setting > 0 ? ` +${(s.latency_setting * 1000).toFixed(0)} ms` : ''}`);
  set('st-time', `${s.time.toFixed(2)} s`);
  set('st-fps', `${fps.toFixed(0)} frames/s`);
  set('st-vein', s.vein ?? 'hidden (exam)');
  set('st-level', s.level ? `${LEVEL_NAMES[s.level] ?? s.level}, ${(s.level_s * 100).toFixed(1)} cm below the groin` : '–');
  // The imaging thread's reading of the section under the probe (issue 13);
  // hidden while an exam question is open (the trainee reads the image).
  const r = s.section;
  set('st-section', r && !(s.exam && s.exam.open)
    ? `${r.vein ?? 'vein'} ${(r.vein_lumen_ratio * 100).toFixed(0)} % of rest${r.walls_met ? ' (walls met)' : ''}, artery ${(r.artery_lumen_ratio * 100).toFixed(0)} %`
    : '–');
  const fault = document.getElementById('fault');
  fault.hidden = !s.fault;
  fault.textContent = s.fault ? `Simulation stopped: ${s.fault}. Press Reset to restart it.` : '';
}
