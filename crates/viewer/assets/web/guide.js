// The guided start (issue 19: "a page a first-time trainee understands"):
// five steps of one compression, each shown over the 3D view and ticked off
// from the live state as the trainee does it — place the probe, find the
// vein, press until its walls meet, release, step along the leg. It opens on
// a first visit, can be skipped or hidden, and comes back with its button.

/** Force (N) above which the probe touches the skin, and below which it is released. */
const TOUCH_N = 0.3;
const RELEASED_N = 0.5;
/**
 * The artery's lumen ratio below which it deforms: the exam's cue that the
 * press went far enough for a vein that will not close (the exam crate's
 * detector uses the same 0.9).
 */
const ARTERY_CUE = 0.9;
/** How far along the leg (m) counts as the next site: the protocol's 1–2 cm steps. */
const STEP_M = 0.015;
const KEY = 'echothigh.guide.done';

const STEPS = [
  {
    text: 'Place the probe on the skin: click or drag on the thigh (or Tab to the view and press Enter).',
    device: 'Place the probe on the skin: move the device\'s stylus until the probe touches the thigh.',
    done: (s, p) => p.placed && s.force > TOUCH_N,
  },
  {
    text: 'Find the vein: the image shows it as a dark oval beside its round, pulsing artery. Drag along the thigh (or ↑/↓) to follow it.',
    device: 'Find the vein: the image shows it as a dark oval beside its round, pulsing artery. Slide the stylus along the thigh to follow it.',
    done: (s) => s.section !== null,
  },
  {
    text: 'Press (wheel, or W) into the blue target band of the force gauge, until the vein\'s walls meet. A vein that stays open while its artery starts to flatten holds a clot.',
    device: 'Press into the thigh, into the blue target band of the force gauge, until the vein\'s walls meet. A vein that stays open while its artery starts to flatten holds a clot.',
    done: (s) => s.section !== null && (s.section.walls_met || s.section.artery_lumen_ratio < ARTERY_CUE),
  },
  {
    text: 'Release (wheel back, or S) until the force is near zero: the vein opens again.',
    device: 'Release until the force is near zero: the vein opens again.',
    done: (s) => s.force < RELEASED_N,
  },
  {
    text: 'Step 1–2 cm along the leg (drag, or ↑/↓) and press again: every site of the exam is pressed like this.',
    device: 'Step 1–2 cm along the leg (clutch and reposition your hand if you run out of reach) and press again: every site of the exam is pressed like this.',
    done: (s, p, g) => s.section !== null && g.at !== null && Math.abs(s.section.s - g.at) > STEP_M,
  },
];

/** The guide's card over the 3D view (`#guide`) and its state. */
export class Guide {
  constructor(root, help, reopen) {
    this.root = root;
    this.help = help;
    this.reopen = reopen;
    this.step = 0;
    this.at = null; // where along the leg (m) the walls were pressed
    this.device = false; // a haptic device drives the probe (issue 15): its texts
    let seen = false;
    try { seen = localStorage.getItem(KEY) === '1'; } catch { /* storage off: show it */ }
    this.active = !seen;
    root.querySelector('[data-act=skip]').addEventListener('click', () => this.advance());
    root.querySelector('[data-act=hide]').addEventListener('click', () => this.close());
    reopen.addEventListener('click', () => { this.step = 0; this.at = null; this.active = true; this.show(); });
    this.show();
  }

  /**
   * Ticks the current step off from the state `s` and the page's probe `p`;
   * `device`: a haptic device drives the probe (its probe is always placed:
   * it touches the skin when the force says so), and the steps say how with it.
   */
  update(s, p, device = false) {
    if (device !== this.device) { this.device = device; this.show(); }
    if (!this.active) return;
    const view = { force: Math.hypot(...s.physics_force), section: s.section || null };
    if (!STEPS[this.step].done(view, device ? { placed: true } : p, this)) return;
    if (this.step === 2 && view.section) this.at = view.section.s;
    this.advance();
  }

  advance() {
    this.step += 1;
    if (this.step >= STEPS.length) this.close();
    else this.show();
  }

  close() {
    this.active = false;
    try { localStorage.setItem(KEY, '1'); } catch { /* nothing to remember it in */ }
    this.show();
  }

  show() {
    this.root.hidden = !this.active;
    this.help.hidden = this.active;
    this.reopen.hidden = this.active;
    if (!this.active) return;
    this.root.dataset.step = String(this.step + 1);
    this.root.querySelector('.guide-n').textContent = `Step ${this.step + 1} of ${STEPS.length}`;
    const step = STEPS[this.step];
    this.root.querySelector('.guide-text').textContent = this.device ? step.device : step.text;
  }
}
