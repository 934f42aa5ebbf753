// The 3D view: the thigh surface deforming and coloured by compression, the
// probe box, the device and proxy markers, the force vectors, a real
// device's workspace. Positions in m, thigh frame (z along the axis, y
// anterior = up), which three.js shows as is. The same class draws in a
// worker on an OffscreenCanvas (scene_worker.js) and, without a renderer,
// answers the page's picks on its thread (scene_proxy.js).
import * as THREE from './vendor/three.module.min.js';

const BACKGROUND = 0x1b2029;
const REST = new THREE.Color(0xecbf9f);
const MID = new THREE.Color(0xe8a33a);
const FULL = new THREE.Color(0xc0262b);
// Arrow length per newton of force (m/N), and its cap (m).
const ARROW_M_PER_N = 0.004;
const ARROW_MAX = 0.12;

/**
 * Colour of a node whose normal spring is compressed by `c` (fraction of its
 * asymptote b/a): a square-root scale, so that the first millimetres show.
 */
function compressionColour(c, out) {
  const t = Math.sqrt(Math.min(Math.max(c, 0), 1));
  if (t < 0.5) out.copy(REST).lerp(MID, t * 2);
  else out.copy(MID).lerp(FULL, (t - 0.5) * 2);
  return out;
}

// The workspace box's 12 edges: corners i and j differ in one bit (bit k
// set: the box's maximum along the device's axis k).
const EDGES = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];

/** Whether WebGL runs on a software rasterizer (SwiftShader, llvmpipe): no GPU. */
export function softwareRenderer() {
  try {
    const probe = typeof document !== 'undefined' ? document.createElement('canvas') : new OffscreenCanvas(1, 1);
    const gl = probe.getContext('webgl2');
    if (!gl) return false;
    const info = gl.getExtension('WEBGL_debug_renderer_info');
    const name = String(info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER));
    const lose = gl.getExtension('WEBGL_lose_context');
    if (lose) lose.loseContext();
    return /swiftshader|llvmpipe|software/i.test(name);
  } catch (_) {
    return false;
  }
}

export class ThighScene {
  /**
   * `canvas`: an HTMLCanvasElement or an OffscreenCanvas; `pixelRatio`:
   * the screen's device pixels per CSS pixel; `draw`: false for a scene
   * that only answers picks (no WebGL context: the canvas draws elsewhere).
   */
  constructor(canvas, pixelRatio = 1, draw = true) {
    this.canvas = canvas;
    this.pixelRatio = Math.min(pixelRatio || 1, 2);
    this.target = new THREE.Vector3();
    this.orbit = { azimuth: 0.75, elevation: 0.45, distance: 0.75 };
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.005, 10);
    this.raycaster = new THREE.Raycaster();
    this.restMesh = null;
    this.onLeg = false;
    this.scale = 1;
    this.dirty = true;
    this.frames = 0;
    this.renderer = null;
    if (!draw) return;
    // On a software renderer (no GPU: SwiftShader or llvmpipe) the page's
    // thread hands every frame to the compositor by a copy, and a
    // multisampled one is resolved first: without antialiasing, and with
    // the drawing buffer swapped rather than preserved, that copy is cheaper
    // (issue 19: it was half the page's thread under a throttled CPU). Tests
    // read the pixels right after a render, in the same task.
    const software = softwareRenderer();
    this.software = software;
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: !software, preserveDrawingBuffer: false });
    this.renderer.setPixelRatio(this.pixelRatio);
    // Resolution scale (1: the screen's pixels): lowered by the page when
    // frames come slowly (software WebGL on a busy laptop), so that drawing
    // the leg does not starve the state handling and the simulation.
    // A software rasterizer draws every pixel on the CPU the simulation
    // shares: start at half the resolution (a quarter of the pixels).
    if (software) this.setScale(0.5);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(BACKGROUND);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.4));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(0.4, 1.0, 0.6);
    this.scene.add(sun);
    this.thigh = null;
    this.workspace = null;
    this.buildProbe();
  }

  buildProbe() {
    // Probe: face 40 mm lateral (local x) × 10 mm elevation (local z); face at
    // local y = 0, body towards +y (ARCHITECTURE.md, contact).
    const height = 0.07;
    const geom = new THREE.BoxGeometry(0.04, height, 0.01);
    geom.translate(0, height / 2, 0);
    this.probe = new THREE.Mesh(geom, new THREE.MeshStandardMaterial({
      color: 0x8fa3bf, transparent: true, opacity: 0.55, roughness: 0.4 }));
    this.probe.add(new THREE.LineSegments(new THREE.EdgesGeometry(geom),
      new THREE.LineBasicMaterial({ color: 0xd6e2f5 })));
    this.probe.visible = false;
    this.scene.add(this.probe);
    const marker = (colour) => {
      const m = new THREE.Mesh(new THREE.SphereGeometry(0.0035, 16, 12),
        new THREE.MeshBasicMaterial({ color: colour, depthTest: false }));
      m.renderOrder = 2;
      m.visible = false;
      this.scene.add(m);
      return m;
    };
    this.deviceMarker = marker(0x3d8bff);
    this.proxyMarker = marker(0x3fd07a);
    const arrow = (colour) => {
      const a = new THREE.ArrowHelper(new THREE.Vector3(0, 1, 0), new THREE.Vector3(), 0.05, colour, 0.012, 0.008);
      a.visible = false;
      a.line.material.depthTest = false;
      a.cone.material.depthTest = false;
      a.renderOrder = 3;
      this.scene.add(a);
      return a;
    };
    this.renderedArrow = arrow(0xff9a1f);
    this.physicsArrow = arrow(0xb071ff);
  }

  /** Builds the thigh from the server's `hello` mesh ({rest: [[x,y,z]], triangles: [[a,b,c]]}). */
  setMesh(mesh) {
    this.dirty = true;
    const n = mesh.rest.length;
    const rest = new Float32Array(n * 3);
    mesh.rest.forEach((p, i) => rest.set(p, i * 3));
    const index = new Uint32Array(mesh.triangles.length * 3);
    mesh.triangles.forEach((t, i) => index.set(t, i * 3));
    if (this.renderer) this.buildThigh(n, rest, index);

    // The rest surface, invisible, is what the mouse ray hits: dragging
    // follows the undeformed surface, as the runtime's (theta, z) expects.
    const restGeom = new THREE.BufferGeometry();
    restGeom.setAttribute('position', new THREE.BufferAttribute(rest, 3));
    restGeom.setIndex(new THREE.BufferAttribute(index, 1));
    restGeom.computeBoundingSphere();
    this.restMesh = new THREE.Mesh(restGeom, new THREE.MeshBasicMaterial({ side: THREE.DoubleSide }));
    this.restMesh.updateMatrixWorld();
    restGeom.computeBoundingBox();
    restGeom.boundingBox.getCenter(this.target);
    // Semi-axes of the elliptic cross-section (centred on the z axis), for
    // the parametric angle of a picked point.
    this.semiX = Math.max(Math.abs(restGeom.boundingBox.min.x), Math.abs(restGeom.boundingBox.max.x));
    this.semiY = Math.max(Math.abs(restGeom.boundingBox.min.y), Math.abs(restGeom.boundingBox.max.y));
    this.orbit.distance = 3.0 * restGeom.boundingSphere.radius;
  }

  /** The drawn thigh of `n` nodes (`rest` 3n positions, `index` triangles). */
  buildThigh(n, rest, index) {
    if (this.thigh) { this.scene.remove(this.thigh); this.thigh.geometry.dispose(); }
    const colours = new Float32Array(n * 3);
    const c = new THREE.Color();
    for (let i = 0; i < n; i++) compressionColour(0, c).toArray(colours, i * 3);

    const geom = new THREE.BufferGeometry();
    geom.setAttribute('position', new THREE.BufferAttribute(rest.slice(), 3));
    geom.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    geom.setIndex(new THREE.BufferAttribute(index, 1));
    geom.computeVertexNormals();
    this.thigh = new THREE.Mesh(geom, new THREE.MeshStandardMaterial({
      vertexColors: true, side: THREE.DoubleSide, roughness: 0.75, metalness: 0.0 }));
    this.scene.add(this.thigh);
  }

  /** Applies a surface frame: `positions` (3n f32, m) and `compression` (n f32, 0..1). */
  updateSurface(positions, compression) {
    this.dirty = true;
    if (!this.thigh) return;
    const geom = this.thigh.geometry;
    const pos = geom.attributes.position;
    if (pos.array.length !== positions.length) return;
    pos.array.set(positions);
    pos.needsUpdate = true;
    const col = geom.attributes.color;
    const c = new THREE.Color();
    for (let i = 0; i < compression.length; i++) compressionColour(compression[i], c).toArray(col.array, i * 3);
    col.needsUpdate = true;
    geom.computeVertexNormals();
    geom.computeBoundingSphere();
  }

  /** Places the probe, markers and force arrows from a `state` message. */
  updateState(s) {
    this.dirty = true;
    this.onLeg = s.level != null;
    if (!this.renderer) return;
    const v = (a) => new THREE.Vector3(a[0], a[1], a[2]);
    const [w, x, y, z] = s.probe_orientation;
    const valid = Math.abs(w * w + x * x + y * y + z * z - 1) < 0.1;
    this.probe.visible = valid;
    if (valid) {
      this.probe.position.copy(v(s.probe_position));
      this.probe.quaternion.set(x, y, z, w);
    }
    this.deviceMarker.visible = this.proxyMarker.visible = true;
    this.deviceMarker.position.copy(v(s.device));
    this.proxyMarker.position.copy(v(s.proxy));
    this.setArrow(this.renderedArrow, v(s.probe_position), v(s.rendered_force));
    this.setArrow(this.physicsArrow, v(s.probe_position), v(s.physics_force));
  }

  setArrow(arrow, origin, force) {
    const magnitude = force.length();
    arrow.visible = magnitude > 0.05;
    if (!arrow.visible) return;
    arrow.position.copy(origin);
    arrow.setDirection(force.clone().divideScalar(magnitude));
    arrow.setLength(Math.min(ARROW_M_PER_N * magnitude, ARROW_MAX) + 0.015, 0.012, 0.008);
  }

  /** The rest-surface point under the pixel (clientX, clientY) as {theta, z}, or null. */
  pick(clientX, clientY) {
    if (!this.restMesh) return null;
    const r = this.canvas.getBoundingClientRect();
    if (r.width === 0 || r.height === 0) return null;
    this.placeCamera(r.width, r.height);
    const ndc = new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    const hit = this.raycaster.intersectObject(this.restMesh, false)[0];
    if (!hit) return null;
    // theta (LiveCommand::Probe), 0 at the anterior (+y) line, increasing
    // towards +x (lateral). On a patient's leg (the state names a level) it
    // is the polar angle about the leg's axis (the runtime's θ_leg = −theta);
    // on the elliptic cylinder, the ellipse's parametric angle: with the
    // model's skin x = a cos θ_m, y = b sin θ_m, theta = π/2 − θ_m.
    const theta = this.onLeg
      ? Math.atan2(hit.point.x, hit.point.y)
      : Math.atan2(hit.point.x / this.semiX, hit.point.y / this.semiY);
    return { theta, z: hit.point.z };
  }

  rotate(dx, dy) {
    this.dirty = true;
    this.orbit.azimuth -= dx * 0.008;
    this.orbit.elevation = Math.min(Math.max(this.orbit.elevation + dy * 0.008, -1.45), 1.45);
  }

  zoom(factor) {
    this.dirty = true;
    this.orbit.distance = Math.min(Math.max(this.orbit.distance * factor, 0.15), 3);
  }

  /** Sets the resolution scale (0.5–1 of the screen's pixels). */
  setScale(scale) {
    const s = Math.min(Math.max(scale, 0.5), 1);
    if (s === this.scale) return;
    this.scale = s;
    if (this.renderer) this.renderer.setPixelRatio(this.pixelRatio * s);
    this.size = null;
    this.dirty = true;
  }

  /**
   * The camera for a view `w` × `h` (CSS pixels) of the orbit about the
   * thigh's centre: the drawing and the picks use the same one.
   */
  placeCamera(w, h) {
    if (this.camera.aspect !== w / h) {
      this.camera.aspect = w / h;
      this.camera.updateProjectionMatrix();
    }
    const o = this.orbit;
    this.camera.position.set(
      this.target.x + o.distance * Math.cos(o.elevation) * Math.sin(o.azimuth),
      this.target.y + o.distance * Math.sin(o.elevation),
      this.target.z + o.distance * Math.cos(o.elevation) * Math.cos(o.azimuth));
    this.camera.lookAt(this.target);
    this.camera.updateMatrixWorld();
  }

  /**
   * The real device's workspace (8 corners, m, or null: hidden) as a
   * dashed box (issue 15).
   */
  setWorkspace(corners) {
    if (!this.renderer) return;
    if (!corners) {
      if (this.workspace && this.workspace.visible) { this.workspace.visible = false; this.dirty = true; }
      return;
    }
    this.dirty = true;
    if (!this.workspace) {
      const geom = new THREE.BufferGeometry();
      geom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(EDGES.length * 6), 3));
      this.workspace = new THREE.LineSegments(geom, new THREE.LineDashedMaterial({
        color: 0x3d8bff, dashSize: 0.01, gapSize: 0.006, transparent: true, opacity: 0.8 }));
      this.scene.add(this.workspace);
    }
    const box = this.workspace;
    box.visible = true;
    const pos = box.geometry.attributes.position;
    EDGES.forEach(([a, b], e) => {
      pos.setXYZ(2 * e, corners[a][0], corners[a][1], corners[a][2]);
      pos.setXYZ(2 * e + 1, corners[b][0], corners[b][1], corners[b][2]);
    });
    pos.needsUpdate = true;
    box.geometry.computeBoundingSphere();
    box.computeLineDistances();
  }

  /** Draws the view, `w` × `h` CSS pixels (the canvas's own size by default). */
  render(w = this.canvas.clientWidth, h = this.canvas.clientHeight) {
    if (!this.renderer || w === 0 || h === 0) return;
    this.dirty = false;
    const size = `${w}x${h}`;
    if (this.size !== size) {
      this.size = size;
      this.renderer.setSize(w, h, false);
    }
    this.placeCamera(w, h);
    this.renderer.render(this.scene, this.camera);
    this.frames += 1;
  }

  /**
   * What the last render drew, read back at once (the drawing buffer is
   * not preserved): the fraction of pixels off the background colour and
   * the count of distinct colours among every 16th pixel, for the browser
   * test.
   */
  ink() {
    const gl = this.renderer.getContext();
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const d = new Uint8Array(4 * w * h);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, d);
    const bg = [d[0], d[1], d[2]];
    let ink = 0;
    const colours = new Set();
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) > 24) ink++;
      if (i % 64 === 0) colours.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
    }
    return { fraction: ink / (w * h), colours: colours.size, width: w, height: h };
  }
}
