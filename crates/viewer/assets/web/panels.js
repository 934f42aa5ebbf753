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

  /**
   * A decoded gray B-mode frame (an ImageBitmap decoded without colour
   * conversion) drawn as it is: one `drawImage`, no per-pixel work on the
   * page's thread (issue 19: under a throttled CPU the pixel loops of
   * `draw` held each image ~0.2 s between arrival and screen).
   */
  drawBitmap(bitmap, decorate = null) {
    const { width, height } = bitmap;
    if (width === 0 || height === 0) return;
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
      this.image = null;
    }
    this.ctx.drawImage(bitmap, 0, 0);
    this.coloured = 0;
    if (decorate) decorate(this.ctx, width, height);
    this.frames += 1;
  }
}

/**
 * The depth scale a scanner draws beside its image (issue 21): a tick every
 * 5 mm, a longer one with its label every centimetre, along the right edge.
 * `depth` is the image's depth (m) from the server's hello; `h` rows span
 * it. Drawn in image pixels, so it scales with the image.
 */
export function drawDepthScale(ctx, w, h, depth) {
  if (!(depth > 0)) return;
  const rowsPerMm = h / (depth * 1000);
  ctx.save();
  ctx.strokeStyle = '#d8d8d8'; ctx.fillStyle = '#d8d8d8'; ctx.lineWidth = 1;
  ctx.font = `${Math.max(10, Math.round(h / 28))}px system-ui, sans-serif`;
  ctx.textAlign = 'right'; ctx.textBaseline = 'middle';
  for (let mm = 5; mm < depth * 1000 - 0.5; mm += 5) {
    const y = Math.round(mm * rowsPerMm) + 0.5;
    const cm = mm % 10 === 0;
    ctx.beginPath(); ctx.moveTo(w, y); ctx.lineTo(w - (cm ? 8 : 4), y); ctx.stroke();
    if (cm) ctx.fillText(String(mm / 10), w - 10, y);
  }
  ctx.restore();
}

/** Clinical abbreviations of the vessels named on the image. */
const VESSEL_NAMES = {
  cfv: 'CFV', cfa: 'CFA', gsv: 'GSV', dfv: 'DFV', dfa: 'DFA', fv: 'FV', fa: 'FA',
  pv: 'PV', pa: 'PA', fv2: 'FV (duplicate)',
};

/**
 * The vessels named over the image (issue 19: a hint in practice mode):
 * each label of the section reading (`labels`: id, lateral and depth of
 * the lumen's centre in m, its half-width and half-height) outlined and
 * named, on an image `width` (m) wide and `depth` (m) deep drawn `w` × `h`
 * pixels. Veins in blue, arteries in red, as on a colour Doppler screen.
 */
export function drawVesselNames(ctx, w, h, labels, width, depth) {
  if (!labels || !(width > 0) || !(depth > 0)) return;
  const sx = w / width, sy = h / depth;
  ctx.save();
  ctx.font = `${Math.max(10, Math.round(h / 26))}px system-ui, sans-serif`;
  ctx.textAlign = 'center'; ctx.textBaseline = 'bottom';
  ctx.lineWidth = 1.5; ctx.setLineDash([4, 3]);
  for (const l of labels) {
    if (!l || !l.id) continue;
    const x = (l.lateral + width / 2) * sx, y = l.depth * sy;
    const rx = Math.max(l.radii[0] * sx, 3), ry = Math.max(l.radii[1] * sy, 3);
    const colour = /a$/.test(l.id) ? '#ff6b6b' : '#6bb6ff';
    ctx.strokeStyle = colour; ctx.fillStyle = colour;
    ctx.beginPath(); ctx.ellipse(x, y, rx, ry, 0, 0, 2 * Math.PI); ctx.stroke();
    // The name stays inside the image, clear of the depth scale on the
    // right edge: beside the outline, on the side towards the centre, when
    // the vessel sits near an edge.
    const name = VESSEL_NAMES[l.id] || l.id.toUpperCase();
    const half = ctx.measureText(name).width / 2 + 2;
    if (x + half > w - 24) { ctx.textAlign = 'right'; ctx.fillText(name, x - rx - 3, y); }
    else if (x - half < 0) { ctx.textAlign = 'left'; ctx.fillText(name, x + rx + 3, y); }
    else { ctx.textAlign = 'center'; ctx.fillText(name, x, y - ry - 2); }
  }
  ctx.restore();
}

/** The force the trainee would feel, against the device limit. */
/**
 * The force gauge (issue 19): the felt force as the bar, the tissue force as
 * a white mark, a scale in N with a labelled tick every 2, 5, 10 or 20 N (at
 * most six), and the device's limit on this leg as a dashed line labelled
 * with its value (the most tissue force the device renders unsaturated: its
 * peak over the force scale, which the scenario fits to the patient).
 */
export class Gauge {
  constructor(box) {
    const q = (sel) => box.querySelector(sel);
    this.bar = q('#gauge');
    this.fill = q('#gauge-fill');
    this.tissue = q('#gauge-tissue');
    this.limit = q('#gauge-limit');
    this.limitLabel = q('#gauge-limit-label');
    this.value = q('#gauge-value');
    this.tissueValue = q('#gauge-tissue-value');
    this.band = q('#gauge-band');
    this.target = q('#gauge-target');
    this.scaleOf = null; // the maxForce the ticks were drawn for
  }

  /** The tick step (N): the smallest of 2, 5, 10, 20 giving at most six ticks up to `top` N. */
  static step(top) {
    return [2, 5, 10, 20].find((d) => top / d <= 6) || 50;
  }

  /** Redraws the ticks for a bar spanning 0 to `top` N. */
  ticks(top) {
    for (const t of this.bar.querySelectorAll('.gauge-tick')) t.remove();
    const d = Gauge.step(top);
    for (let f = d; f < top; f += d) {
      // No tick label where the limit's label stands (within 10 % of the bar).
      if (Math.abs(f - this.scaleOf) < 0.1 * top) continue;
      const t = document.createElement('div');
      t.className = 'gauge-tick';
      t.style.bottom = `${((f / top) * 100).toFixed(1)}%`;
      t.textContent = `${f}`;
      this.bar.appendChild(t);
    }
  }

  /**
   * `felt` and `tissue` forces (N, tissue units); `maxForce` (N): the
   * device's limit in tissue units; `band`: the target band under the probe
   * `[walls meet, artery clearly oval]` (N of tissue force, the section
   * reading's `target_band`), or null / `[0, 0]` for none.
   */
  update(felt, tissue, maxForce, band) {
    const top = Math.max(maxForce * 1.25, 1);
    if (this.scaleOf !== maxForce) {
      this.scaleOf = maxForce;
      this.ticks(top);
      this.limit.style.bottom = `${((maxForce / top) * 100).toFixed(1)}%`;
      this.limitLabel.textContent = `${maxForce.toFixed(0)} N`;
      this.limit.title = `device limit: ${maxForce.toFixed(1)} N of tissue force on this leg`;
      this.bar.setAttribute('aria-valuemax', maxForce.toFixed(1));
    }
    const pct = (f) => `${(Math.min(f / top, 1) * 100).toFixed(1)}%`;
    this.fill.style.height = pct(felt);
    this.fill.style.background = felt > maxForce ? '#c0262b' : felt > 0.7 * maxForce ? '#e8a33a' : '#3fd07a';
    this.tissue.style.bottom = pct(tissue);
    this.value.textContent = `${felt.toFixed(1)} N`;
    this.tissueValue.textContent = `tissue ${tissue.toFixed(1)} N`;
    this.bar.setAttribute('aria-valuenow', felt.toFixed(1));
    const on = Array.isArray(band) && band[1] > band[0] && band[0] >= 0;
    this.band.hidden = !on;
    this.target.hidden = !on;
    if (on) {
      const [lo, hi] = band.map((f) => Math.min(f / top, 1) * 100);
      this.band.style.bottom = `${lo.toFixed(1)}%`;
      this.band.style.height = `${(hi - lo).toFixed(1)}%`;
      const fmt = (f) => f.toFixed(f < 10 ? 1 : 0);
      this.target.textContent = `target ${fmt(band[0])}–${fmt(band[1])}\u00a0N`;
      this.band.title = `target: a healthy vein here meets its walls at ${band[0].toFixed(1)} N; its artery is clearly oval at ${band[1].toFixed(1)} N (tissue force)`;
    }
  }
}

/** |F| of the rendered and the physics force over the last `span` seconds. */
export class ForcePlot {
  constructor(canvas, span = 5) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.span = span;
    this.samples = []; // [t (s), rendered (N), physics (N)]
    this.dirty = true; // samples came since the last draw
  }

  push(t, rendered, physics) {
    const last = this.samples[this.samples.length - 1];
    if (last && t < last[0]) this.samples.length = 0; // time went back: a reset
    if (last && t === last[0]) return;
    this.samples.push([t, rendered, physics]);
    this.dirty = true;
    while (this.samples.length && this.samples[0][0] < t - this.span) this.samples.shift();
  }

  draw() {
    this.dirty = false;
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

/** The live imaging thread's schedule (frames/s; runtime `IMAGING_RATE_SETTING`). */
export const IMAGING_RATE = 20;

export function showStatus(s, fps) {
  const set = (id, text) => { document.getElementById(id).textContent = text; };
  set('st-physics', `${s.physics_rate.toFixed(0)} Hz (set ${s.physics_rate_setting.toFixed(0)})`);
  // The haptic thread's scheduling (issue 19): real-time where permitted.
  const prio = { realtime: 'real-time priority', raised: 'raised priority (real-time refused)', normal: 'normal priority' };
  set('st-haptic', `${s.haptic_rate.toFixed(0)} Hz, ${prio[s.haptic_priority] ?? s.haptic_priority}`);
  set('st-missed', `${s.missed_deadlines}`);
  set('st-age', `${(s.model_age * 1000).toFixed(1)} ms`);
  set('st-mode', `${s.mode ?? '–'}${s.latency_setting > 0 ? ` +${(s.latency_setting * 1000).toFixed(0)} ms` : ''}`);
  set('st-time', `${s.time.toFixed(2)} s`);
  // The ultrasound image's achieved rate (issue 19), 0 before its first second.
  const image = s.imaging_rate > 0 ? `; image ${s.imaging_rate.toFixed(0)} of ${IMAGING_RATE}` : '';
  set('st-fps', `${fps.toFixed(0)} frames/s${image}`);
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
