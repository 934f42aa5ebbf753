// The exam panel (issue 14): the case's vignette, the protocol's checklist
// with a call per site, the coverage strip along the leg (live), and after
// the case the truth drawn under the trainee's coverage. The server keeps
// the truth until the case is finished; this module only draws what it sent.

const $ = (id) => document.getElementById(id);

// Finding names of the protocol (crates/exam Finding) and their labels.
export const FINDINGS = [
  ['normal', 'normal (compresses)'],
  ['acute_dvt', 'acute DVT'],
  ['chronic_post_thrombotic', 'chronic post-thrombotic'],
  ['indeterminate', 'indeterminate (inadequate study)'],
];
// Doppler readings (crates/exam doppler: flow pattern, augmentation on a calf
// squeeze) as one select value `flow:0|1`.
export const DOPPLER = ['phasic', 'continuous', 'absent'].flatMap((flow) => [true, false].map((aug) =>
  [`${flow}:${aug ? 1 : 0}`, `${flow}, ${aug ? 'augments' : 'no augmentation'}`]));
const dopplerValue = (f) => (f ? `${f.flow}:${f.augments ? 1 : 0}` : '');
// Coverage bin colours (BinState) and truth colours (ground-truth kinds).
const BIN_COLOUR = {
  not_examined: '#39414f', inadequate_pressure: '#d9a400', not_closed: '#ff5a4f', closed: '#3fd07a',
};
const TRUTH_COLOUR = (kind) => (kind === 'normal' ? '#6f7a8a' : kind === 'chronic' ? '#b071ff' : '#c0262b');

/** Draws the exam panel from the server's exam status `e`; `levelS` is the
 *  probe's place along the leg (m below the inguinal ligament) for the strip's
 *  marker; `send` sends a page command. */
export function showExam(e, levelS, send) {
  if (!e) return;
  $('exam-start').textContent = e.cases_done > 0 || e.open ? 'Next case' : 'Start a case';
  $('exam-start').disabled = e.open;
  $('exam-finish').disabled = !e.open;
  $('exam-stop').disabled = !e.active;
  // The instructions make room for the checklist while a case is open.
  $('exam-help').hidden = e.open;
  const who = e.trainee ? `${e.trainee} · ` : '';
  $('exam-meta').textContent = e.active || e.cases_done ?
    `${who}${e.protocol} · case ${e.case_number} of ${e.cases_total} · ${e.recording}` : '';
  const v = e.vignette;
  $('exam-vignette').textContent = v ? `Patient ${v.age} y: ${v.symptoms} (Wells ${v.wells})` : '';
  showSites(e, send);
  $('exam-status').textContent = e.open ?
    `${e.presses} compressions · peak ${e.peak_force.toFixed(1)} N` :
    (e.cases_done ? `session: ${e.cases_done} cases, calls right ${e.calls_correct} / ${e.calls_total}` : '');
  // A records fault (the database failed: where the records are kept) is
  // already the meta's `recording`; other errors go here.
  if (e.error && e.error !== e.recording) $('exam-status').textContent += ` · ${e.error}`;
  showResult(e);
  drawStrip($('coverage'), e.open ? e.coverage : (e.last ? e.last.coverage : []),
    e.open ? e.sites : [], e.open ? null : (e.last ? e.last.truth : null), levelS);
}

/** The checklist: one row per site, its pressed mark and its call. */
function showSites(e, send) {
  const table = $('exam-sites');
  const doppler = e.open ? (e.doppler || []) : [];
  const key = e.open ? `${e.case_number}:${e.sites.map((x) => x.name).join(',')}` : '';
  if (table.dataset.key !== key) {
    table.dataset.key = key;
    table.replaceChildren(...e.sites.map((x) => {
      const tr = document.createElement('tr');
      const name = document.createElement('th');
      name.textContent = `${x.name}`;
      name.title = `${x.vein} at ${(x.s * 1000).toFixed(0)} mm below the inguinal ligament`;
      const done = document.createElement('td');
      done.className = 'done';
      const td = document.createElement('td');
      const sel = document.createElement('select');
      sel.dataset.site = x.name;
      sel.setAttribute('aria-label', `call at ${x.name}`);
      const none = new Option('— call —', '');
      none.disabled = true;
      sel.append(none, ...FINDINGS.map(([v, label]) => new Option(label, v)));
      sel.addEventListener('change', () => send({ type: 'exam_call', site: x.name, finding: sel.value }));
      td.append(sel);
      tr.append(name, done, td);
      return tr;
    }), ...doppler.map((x) => {
      // One select per Doppler site (spectral Doppler of the CFV and the
      // popliteal vein, SRU 2018).
      const tr = document.createElement('tr');
      const name = document.createElement('th');
      name.textContent = `${x.name} Doppler`;
      name.title = `spectral Doppler of the ${x.vein}: flow pattern and calf-squeeze augmentation`;
      const td = document.createElement('td');
      td.colSpan = 2;
      const sel = document.createElement('select');
      sel.dataset.doppler = x.name;
      sel.setAttribute('aria-label', `Doppler at ${x.name}`);
      const none = new Option('— Doppler —', '');
      none.disabled = true;
      sel.append(none, ...DOPPLER.map(([v, label]) => new Option(label, v)));
      sel.addEventListener('change', () => {
        const [flow, aug] = sel.value.split(':');
        send({ type: 'exam_doppler', site: x.name, flow, augments: aug === '1' });
      });
      td.append(sel);
      tr.append(name, td);
      return tr;
    }));
  }
  doppler.forEach((x, j) => {
    const tr = table.rows[e.sites.length + j];
    const sel = tr && tr.cells[1].firstChild;
    if (sel && document.activeElement !== sel) sel.value = dopplerValue(x.call);
  });
  e.sites.forEach((x, i) => {
    const tr = table.rows[i];
    if (!tr) return;
    tr.cells[1].textContent = x.done ? 'pressed ✓' : 'not yet';
    tr.cells[1].className = x.done ? 'done yes' : 'done';
    const sel = tr.cells[2].firstChild;
    if (document.activeElement !== sel) sel.value = x.call ?? '';
  });
}

/** The last finished case: its truth and score. */
function showResult(e) {
  const r = e.last;
  const el = $('exam-result');
  if (!r || e.open) { el.textContent = ''; el.className = ''; return; }
  const sc = r.score;
  const wrong = sc.sites.filter((x) => x.call !== x.truth)
    .map((x) => `${x.site}: called ${x.call ?? 'nothing'}, truth ${x.truth}` +
      (x.called_without_adequate_pressure ? ' (without adequate pressure)' : ''));
  const missed = (sc.missed || []).map((m) => `${m.truth} in ${m.vein} ${(m.s_start * 1000).toFixed(0)}–` +
    `${(m.s_end * 1000).toFixed(0)} mm never examined`);
  const dp = sc.doppler && sc.doppler.total ? sc.doppler : null;
  const dwrong = dp ? dp.sites.filter((x) => dopplerValue(x.call) !== dopplerValue(x.truth))
    .map((x) => `${x.site} Doppler: called ${x.call ? x.call.flow : 'nothing'}, truth ${x.truth.flow}` +
      `${x.truth.augments ? ' augmenting' : ' not augmenting'}`) : [];
  el.textContent = `${r.title}: ${r.diagnosis.replaceAll('_', ' ')}. Calls ${sc.calls_correct} / ${sc.calls_total}, ` +
    (dp ? `Doppler ${dp.correct} / ${dp.total}, ` : '') +
    `coverage ${(sc.coverage * 100).toFixed(0)} %, adequate pressure ${(sc.pressure_adequate * 100).toFixed(0)} % of presses, ` +
    `peak ${sc.peak_force.toFixed(1)} N` + (sc.excessive_force_on_tail ? `, ${sc.excessive_force_on_tail} hard presses on a free-floating thrombus` : '') +
    (wrong.length ? `. ${wrong.join('; ')}` : '') + (dwrong.length ? `. ${dwrong.join('; ')}` : '') + (missed.length ? `. Missed: ${missed.join('; ')}` : '') +
    (r.teaching ? `. ${r.teaching}` : '');
  el.className = sc.calls_correct === sc.calls_total && !missed.length ? 'right' : 'wrong';
}

/** The coverage strip: groin (left) to knee (right), one cell per 2 cm bin
 *  coloured by what the presses showed; the protocol's sites as ticks; the
 *  probe's level as a white line; after the case, the truth as a second row. */
function drawStrip(canvas, bins, sites, truth, levelS) {
  const ctx = canvas.getContext('2d');
  const w = canvas.width, h = canvas.height;
  ctx.clearRect(0, 0, w, h);
  if (!bins.length) return;
  const s0 = bins[0].s_start, s1 = bins[bins.length - 1].s_end;
  const x = (s) => ((s - s0) / (s1 - s0)) * (w - 2) + 1;
  const row = truth ? (h - 14) / 2 : h - 14;
  for (const b of bins) {
    ctx.fillStyle = BIN_COLOUR[b.state] ?? '#39414f';
    ctx.fillRect(x(b.s_start), 0, Math.max(1, x(b.s_end) - x(b.s_start) - 1), row);
  }
  if (truth) {
    for (const t of truth.filter((t) => ['cfv', 'fv', 'pv'].includes(t.vein))) {
      ctx.fillStyle = TRUTH_COLOUR(t.kind);
      ctx.fillRect(x(Math.max(s0, t.s_start)), row + 2, Math.max(1, x(Math.min(s1, t.s_end)) - x(Math.max(s0, t.s_start))), row);
    }
  }
  ctx.fillStyle = '#e6e9ee';
  for (const st of sites) ctx.fillRect(x(st.s) - 1, 0, 2, 4);
  if (levelS != null && levelS >= s0 && levelS <= s1) ctx.fillRect(x(levelS) - 1, 0, 2, row);
  ctx.fillStyle = '#8d96a5';
  ctx.font = '10px system-ui';
  ctx.textBaseline = 'bottom';
  ctx.fillText('groin', 2, h);
  const knee = 'knee';
  ctx.fillText(knee, w - ctx.measureText(knee).width - 2, h);
  if (truth) ctx.fillText('truth ↑ (red acute, purple chronic)', 40, h);
}
