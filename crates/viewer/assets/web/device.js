// A real haptic device driving the probe (issue 15): its strip over the top
// of the 3D view (name, clutch, the force it renders next to the tissue
// force, whether it still answers) and its workspace, the device's reach mapped on the leg by the
// calibration, drawn as a box in the 3D view. The state's `haptic_device`
// is null while the mouse drives; then all of this stays hidden.
import { norm } from './panels.js';

/** Whether a device drives the probe (the page's probe controls are off). */
export function deviceDrives(s) {
  return !!(s && s.haptic_device);
}

/** Shows the device's panel and workspace for state `s` (hidden without a device). */
export function showDevice(s, scene) {
  const d = s.haptic_device;
  const panel = document.getElementById('device-box');
  panel.hidden = !d;
  for (const id of ['lift', 'play']) document.getElementById(id).disabled = !!d;
  // The mouse's help line gives way to the device's strip (a class, not the
  // line's `hidden`, which the guided start owns).
  document.body.classList.toggle('device-drives', !!d);
  if (scene) scene.setWorkspace(d ? d.workspace : null);
  if (!d) return;
  const set = (id, text) => { document.getElementById(id).textContent = text; };
  set('dev-name', d.name);
  const state = !d.connected ? 'lost' : d.clutched ? 'clutched' : 'engaged';
  const el = document.getElementById('dev-state');
  el.textContent = !d.connected
    ? `lost: ${d.lost ?? 'it stopped answering'}`
    : d.clutched ? 'clutched: force off, reposition your hand' : 'engaged';
  el.className = `dev-${state}`;
  set('dev-force', `${norm(d.force).toFixed(2)} N of ${d.max_force.toFixed(1)} N`);
  set('dev-tissue', `${norm(s.rendered_force).toFixed(1)} N`);
  set('dev-pose', d.orientation_sensed ? 'stylus orientation' : 'normal to the skin');
  set('dev-reach', d.workspace ? 'dashed blue box' : 'not reported by the device');
}
