// The 3D view drawn off the page's thread (issue 19): on a machine without a
// GPU the compositor reads every WebGL frame back from the software
// rasterizer, and on the page's thread that read held it ~2 s in 6 (a
// throttled CPU): states, images and acknowledgements waited behind it. Here
// the view draws on an OffscreenCanvas in this worker; the page
// (scene_proxy.js) sends it the mesh, the surface, the state and the
// camera, and asks for frames.
import { ThighScene } from './scene.js';

let scene = null;

self.onmessage = (e) => {
  const m = e.data;
  try {
    if (m.type === 'init') {
      scene = new ThighScene(m.canvas, m.pixelRatio);
      self.postMessage({ type: 'ready', software: scene.software, scale: scene.scale });
      return;
    }
    if (!scene) return;
    switch (m.type) {
      case 'mesh': scene.setMesh(m.mesh); break;
      case 'surface': scene.updateSurface(m.pos, m.comp); break;
      case 'state': scene.updateState(m.s); break;
      case 'workspace': scene.setWorkspace(m.corners); break;
      case 'scale': scene.setScale(m.scale); break;
      case 'render': {
        const t = performance.now();
        Object.assign(scene.orbit, m.orbit);
        scene.target.set(m.target[0], m.target[1], m.target[2]);
        scene.render(m.w, m.h);
        // The test reads the pixels in the task that drew them.
        const ink = m.ink ? scene.ink() : null;
        self.postMessage({ type: 'rendered', cost: performance.now() - t, ink });
        break;
      }
      default: break;
    }
  } catch (err) {
    self.postMessage({ type: 'error', message: String((err && err.message) || err) });
  }
};
