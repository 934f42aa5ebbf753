// Doppler in the page (issue 17): the mode buttons (B-mode, colour, power,
// spectral), the manoeuvres (calf squeeze; Valsalva held while the button
// or the V key is down), the colour overlay's palette, the PW sample gate
// placed by clicking the image, the scrolling spectrogram with its
// velocity scale, and the sound synthesized from the spectral lines.
// Protocol: the server's `protocol.rs` (commands `doppler_mode`, `squeeze`,
// `valsalva`, `doppler_gate`; frames 6/7 image + overlay, 8 spectral lines).

const ROWS = 64; // rows of a spectral line (SPECTRAL_ROWS)
const DYNAMIC_RANGE_DB = 40; // the display's log range (SpectralDisplay)
const SCALE_MARGIN = 52; // px at the right of the trace for the velocity labels

/** The overlay code's RGB (the runtime's `code_rgb`, exactly). */
function palette(mode) {
  const p = new Uint8Array(256 * 3);
  for (let c = 1; c < 256; c++) {
    let rgb;
    if (mode === 'power') {
      const s = (c - 1) / 254;
      rgb = [Math.floor(120 + 135 * s), Math.floor(40 + 150 * s), Math.floor(20 * s)];
    } else {
      const f = (c - 128) / 127, s = Math.min(Math.abs(f), 1);
      const hi = Math.floor(110 + 145 * s), lo = Math.floor(60 * s * s);
      rgb = f > 0 ? [hi, lo, 0] : [0, lo, hi];
    }
    p.set(rgb, 3 * c);
  }
  return p;
}
const PALETTES = { color: palette('color'), power: palette('power') };

/**
 * The sound of the spectral lines, synthesized here with the Web Audio API:
 * each row of a line is a sinusoid at its Doppler shift (the row's
 * frequency, signed), its amplitude the row's magnitude with the display's
 * 40 dB log compression undone; each row's phase is carried from line to
 * line (random at the start) and its amplitude ramped linearly across the
 * line, so the lines join without clicks. Positive shifts (flow towards the
 * probe) play on the left, negative on the right, as a scanner's stereo
 * Doppler sound (and as `AudioSynth` writes the WAV of `echothigh doppler`).
 * Each message's lines become one stereo AudioBuffer, queued right after
 * the previous one; a queue more than 0.4 s ahead (a page that fell
 * behind) is dropped rather than played late. Muted until the trainee turns
 * it on: browsers let a page start sound only after a user gesture.
 */
class DopplerAudio {
  constructor() {
    this.ctx = null; this.on = false; this.at = 0;
    this.phase = new Float64Array(ROWS).map(() => Math.random() * 2 * Math.PI);
    this.last = new Float32Array(ROWS); this.gain = 0.1;
  }
  async toggle() {
    this.on = !this.on;
    if (this.on && !this.ctx) this.ctx = new AudioContext();
    if (this.ctx) await (this.on ? this.ctx.resume() : this.ctx.suspend());
    return this.on;
  }
  /** `lines`: Uint8Array of n × ROWS; `interval` s a line; `prf` Hz. */
  play(lines, n, interval, prf) {
    if (!this.on || !this.ctx || n === 0) return;
    const ctx = this.ctx, rate = ctx.sampleRate, per = Math.round(interval * rate);
    const buf = ctx.createBuffer(2, n * per, rate);
    const left = buf.getChannelData(0), right = buf.getChannelData(1);
    const amp = new Float32Array(ROWS);
    for (let l = 0; l < n; l++) {
      let power = 0;
      for (let r = 0; r < ROWS; r++) {
        const m = lines[l * ROWS + r];
        amp[r] = m > 0 ? Math.pow(10, ((m / 255 - 1) * DYNAMIC_RANGE_DB) / 20) : 0;
        power += amp[r] * amp[r];
      }
      // A slow automatic level: about 0.2 RMS whatever the gain of the trace.
      this.gain += 0.05 * (0.2 / Math.sqrt(Math.max(power, 1e-4)) - this.gain);
      for (let r = 0; r < ROWS; r++) {
        const a0 = this.last[r], a1 = amp[r];
        if (a0 < 1e-3 && a1 < 1e-3) continue;
        const f = prf / 2 - ((r + 0.5) / ROWS) * prf;
        const out = f >= 0 ? left : right, w = (2 * Math.PI * Math.abs(f)) / rate;
        let ph = this.phase[r];
        for (let k = 0; k < per; k++) {
          out[l * per + k] += this.gain * (a0 + ((a1 - a0) * k) / per) * Math.sin(ph);
          ph += w;
        }
        this.phase[r] = ph % (2 * Math.PI);
      }
      this.last.set(amp);
    }
    const now = ctx.currentTime;
    if (this.at < now + 0.02 || this.at > now + 0.4) this.at = now + 0.05;
    const src = ctx.createBufferSource();
    src.buffer = buf; src.connect(ctx.destination); src.start(this.at);
    this.at += buf.duration;
  }
}

/** The scrolling spectrogram, newest line at the right, velocity labels on the right. */
class Spectrogram {
  constructor(canvas) {
    this.canvas = canvas; this.ctx = canvas.getContext('2d');
    this.lines = 0; this.col = new ImageData(1, ROWS);
  }
  draw(lines, n, status) {
    const { canvas, ctx } = this, w = canvas.width - SCALE_MARGIN, h = canvas.height;
    const step = Math.max(1, Math.round(w / 800)); // px a line (800 lines = 4 s)
    const shift = Math.min(n * step, w);
    ctx.drawImage(canvas, shift, 0, w - shift, h, 0, 0, w - shift, h);
    for (let l = Math.max(0, n - Math.floor(w / step)); l < n; l++) {
      const d = this.col.data;
      for (let r = 0; r < ROWS; r++) {
        const m = lines[l * ROWS + r];
        d[4 * r] = m; d[4 * r + 1] = m; d[4 * r + 2] = m; d[4 * r + 3] = 255;
      }
      const x = w - (n - l) * step;
      // One line: a 1×ROWS column stretched to step × h.
      const tmp = this.tmp || (this.tmp = new OffscreenCanvas(1, ROWS));
      tmp.getContext('2d').putImageData(this.col, 0, 0);
      ctx.imageSmoothingEnabled = false;
      ctx.drawImage(tmp, 0, 0, 1, ROWS, x, 0, step, h);
    }
    this.lines += n;
    this.scale(status);
  }
  /** The velocity scale (cm/s, angle-corrected) and the baseline. */
  scale(status) {
    const { ctx, canvas } = this, w = canvas.width - SCALE_MARGIN, h = canvas.height;
    ctx.fillStyle = '#0c0f14'; ctx.fillRect(w, 0, SCALE_MARGIN, h);
    ctx.strokeStyle = '#3d8bff'; ctx.beginPath(); ctx.moveTo(0, h / 2); ctx.lineTo(w, h / 2); ctx.stroke();
    if (!status || !status.prf) return;
    const vmax = (status.prf / 2) * status.velocity_per_hz * 100; // cm/s at the top
    ctx.fillStyle = '#c8ced8'; ctx.font = '11px system-ui';
    for (const f of [1, 0.5, 0, -0.5, -1]) {
      const y = h / 2 - (f * h) / 2;
      ctx.fillText(`${(f * vmax).toFixed(0)}`, w + 4, Math.min(Math.max(y + 4, 10), h - 2));
    }
    ctx.fillText('cm/s', w + 4, 22);
  }
}

/**
 * Wires the Doppler controls: `send(msg)` sends a command; the returned
 * object takes the state's `doppler` status, the overlay frames and the
 * spectral lines from app.js.
 */
export function setupDoppler($, send) {
  const audio = new DopplerAudio();
  const spectrum = new Spectrogram($('spectrum'));
  const d = { status: null, audio, linesShown: 0 };
  const radios = [...document.querySelectorAll('input[name="dmode"]')];
  for (const r of radios) r.addEventListener('change', () => { if (r.checked) send({ type: 'doppler_mode', mode: r.value }); });
  $('squeeze').addEventListener('click', () => send({ type: 'squeeze' }));
  // Valsalva is held: the strain lasts while the button (or V) is down.
  const hold = (on) => {
    if (d.held === on) return;
    d.held = on;
    $('valsalva').setAttribute('aria-pressed', String(on));
    send({ type: 'valsalva', hold: on });
  };
  const vb = $('valsalva');
  vb.addEventListener('pointerdown', () => hold(true));
  for (const ev of ['pointerup', 'pointerleave', 'pointercancel', 'blur']) vb.addEventListener(ev, () => hold(false));
  vb.addEventListener('keydown', (e) => { if (e.key === ' ' || e.key === 'Enter') { e.preventDefault(); hold(true); } });
  vb.addEventListener('keyup', (e) => { if (e.key === ' ' || e.key === 'Enter') hold(false); });
  $('audio').addEventListener('click', async () => {
    const on = await audio.toggle();
    $('audio').setAttribute('aria-pressed', String(on));
    $('audio').textContent = on ? 'Sound on' : 'Sound off';
  });
  const angle = $('angle');
  angle.addEventListener('input', () => { $('angle-v').textContent = angle.value; });
  const gate = (x, y) => send({ type: 'doppler_gate', x, y, angle_deg: Number(angle.value) });
  angle.addEventListener('change', () => { const g = d.status && d.status.gate; gate(g ? g.x : 0.5, g ? g.y : 0.4); });
  // The gate: a click on the image, in image fractions (object-fit: contain).
  const echo = $('echo');
  echo.addEventListener('click', (e) => {
    if (!d.status || d.status.mode !== 'spectral') return;
    const r = echo.getBoundingClientRect();
    const k = Math.min(r.width / echo.width, r.height / echo.height);
    const x = (e.clientX - r.left - (r.width - k * echo.width) / 2) / (k * echo.width);
    const y = (e.clientY - r.top - (r.height - k * echo.height) / 2) / (k * echo.height);
    if (x >= 0 && x <= 1 && y >= 0 && y <= 1) gate(x, y);
  });
  // Shortcuts only while the leg (the 3D view) has focus, as app.js's.
  const scene = $('scene');
  scene.addEventListener('keydown', (e) => {
    const k = e.key.toLowerCase();
    if (k === 'c' && !e.repeat) send({ type: 'squeeze' });
    else if (k === 'v') hold(true);
    else return;
    e.preventDefault();
  });
  scene.addEventListener('keyup', (e) => { if (e.key.toLowerCase() === 'v') hold(false); });
  scene.addEventListener('blur', () => hold(false));

  d.update = (s) => {
    d.status = s || null;
    $('doppler-controls').hidden = !s || !s.available;
    $('manoeuvres').hidden = !s || !s.available;
    if (!s) return;
    $('spectral-controls').hidden = s.mode !== 'spectral';
    for (const r of radios) if (document.activeElement !== r) r.checked = r.value === s.mode;
    $('spectrum-box').hidden = s.mode !== 'spectral';
    const scale = s.mode === 'color' || s.mode === 'power'
      ? `colour scale ±${(s.color_nyquist * 100).toFixed(1)} cm/s along the beam (red towards the probe)`
      : s.mode === 'spectral'
        ? `gate ${s.gate_in_flow ? 'in flow' : 'outside flow'} · angle ${s.gate.angle_deg.toFixed(0)}°`
        : '';
    $('doppler-scale').textContent = scale;
    if (document.activeElement !== angle) { angle.value = s.gate.angle_deg; $('angle-v').textContent = s.gate.angle_deg.toFixed(0); }
  };
  /** The palette of the overlay in the current mode. */
  d.palette = () => PALETTES[d.status && d.status.mode === 'power' ? 'power' : 'color'];
  d.lines = (lines, n, interval) => {
    spectrum.draw(lines, n, d.status);
    d.linesShown = (d.linesShown || 0) + n;
    if (d.status) audio.play(lines, n, interval, d.status.prf);
  };
  return d;
}
