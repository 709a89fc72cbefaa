// The console's 3D view: a capture's display glTF (reconstruction/strands/
// hair.display.glb, written by `hairrig reconstruct` and `hairrig export`)
// drawn with three.js r111 (Debian's libjs-three, served under /vendor/).
//
// The file's nodes, by name (rig/gltf_export.h): "strands" (LINES), "truth"
// (LINES, simulated captures only), "points" (POINTS, coloured by direction),
// "head" (TRIANGLES) and an animated node per simulation (its frames as
// children, shown in turn). Units are metres, +y up.
//
// Drawing is on demand: a frame is drawn when the camera moves, a toggle
// changes or the simulation plays, so an idle view costs nothing. While the
// camera moves, at most MOVING_STRANDS of the reconstructed strands are drawn
// (every k-th, through every 2nd point; all again when it stops): without a
// GPU, chromium draws lines in software at about 500,000 segments a second.
// Antialiasing is off on a software renderer (SwiftShader, llvmpipe), where
// it costs about half the frame rate.
import * as THREE from '/vendor/three/build/three.module.js';
import { OrbitControls } from '/vendor/three/examples/jsm/controls/OrbitControls.js';
import { GLTFLoader } from '/vendor/three/examples/jsm/loaders/GLTFLoader.js';

const BACKGROUND = 0x15181d;
const MOVING_STRANDS = 1000;
const GOLDEN_RATIO = 0.618033988749895;

// A unit direction in glTF's frame as the export colours points: red |x|,
// green |y| and blue |z| of the turntable frame (x, -z, y here), so that
// vertical hair is blue.
function directionColour(dx, dy, dz, out, at) {
  const n = Math.hypot(dx, dy, dz) || 1;
  out[at] = Math.abs(dx) / n;
  out[at + 1] = Math.abs(dz) / n;
  out[at + 2] = Math.abs(dy) / n;
}

// Per-vertex colours of a LINES geometry: each vertex takes its segment's
// direction ('direction'), its strand's own hue ('strand') or its wisp's
// ('wisp': the guide it follows, where the export wrote _WISP_ID).
function strandColours(geometry, mode) {
  const position = geometry.attributes.position.array;
  const colours = new Float32Array(position.length);
  if (mode === 'strand' || mode === 'wisp') {
    const ids = (mode === 'wisp' ? geometry.attributes._wisp_id : geometry.attributes._strand_id)?.array;
    const colour = new THREE.Color();
    for (let v = 0; v < position.length / 3; v += 1) {
      const id = ids ? ids[v] : 0;
      colour.setHSL((id * GOLDEN_RATIO) % 1, 0.65, 0.55);
      colours.set([colour.r, colour.g, colour.b], 3 * v);
    }
    return colours;
  }
  const index = geometry.index.array;
  for (let i = 0; i < index.length; i += 2) {
    const a = 3 * index[i], b = 3 * index[i + 1];
    const dx = position[b] - position[a], dy = position[b + 1] - position[a + 1];
    const dz = position[b + 2] - position[a + 2];
    directionColour(dx, dy, dz, colours, a);
    directionColour(dx, dy, dz, colours, b);
  }
  return colours;
}

// Whether WebGL here is drawn in software (no GPU), from a throwaway context.
function softwareRenderer() {
  const gl = document.createElement('canvas').getContext('webgl');
  const info = gl?.getExtension('WEBGL_debug_renderer_info');
  const name = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : '';
  gl?.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|software/i.test(name);
}

// A LINES object drawing every k-th strand of `lines` (at most `max`
// strands) through every 2nd of its points, sharing its vertices (a strand's
// vertices are contiguous, as rig/gltf_export.h writes them).
function coarseStrands(lines, max) {
  const ids = lines.geometry.attributes._strand_id?.array;
  if (!ids || ids.length === 0) return null;
  const k = Math.max(1, Math.ceil((ids[ids.length - 1] + 1) / max));
  const kept = [];
  for (let first = 0; first < ids.length;) {
    let last = first;
    while (last + 1 < ids.length && ids[last + 1] === ids[first]) last += 1;
    if (ids[first] % k === 0) {
      for (let v = first; v < last; v += 2) kept.push(v, Math.min(v + 2, last));
    }
    first = last + 1;
  }
  const geometry = new THREE.BufferGeometry();
  for (const [name, attribute] of Object.entries(lines.geometry.attributes)) geometry.setAttribute(name, attribute);
  geometry.setIndex(kept);
  const coarse = new THREE.LineSegments(geometry, lines.material);
  coarse.visible = false;
  coarse.userData.coarse = true;
  return coarse;
}

function linesUnder(object) {
  const lines = [];
  object?.traverse((o) => { if (o.isLineSegments && !o.userData.coarse) lines.push(o); });
  return lines;
}

export class HairViewer {
  // `canvas`: the element drawn into. Throws when WebGL is unavailable.
  constructor(canvas) {
    this.canvas = canvas;
    this.software = softwareRenderer();
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: !this.software });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(BACKGROUND);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x303030, 0.9));
    const key = new THREE.DirectionalLight(0xffffff, 0.7);
    key.position.set(1, 2, 1.5);
    this.scene.add(key);
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.01, 20);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.addEventListener('change', () => this.requestDraw());
    this.controls.addEventListener('start', () => this.setMoving(true));
    this.controls.addEventListener('end', () => this.setMoving(false));
    this.moving = false;
    this.coarse = null;  // the strands drawn while the camera moves
    this.clock = new THREE.Clock(false);
    this.model = null;
    this.parts = {};
    this.shown = {};
    this.mixer = null;
    this.action = null;
    this.playing = false;
    this.loads = 0;
    this.colourMode = 'direction';
    this.framesDrawn = 0;
    this.firstFrameAt = null;  // performance.now() of the first frame of a loaded model
    this.pending = false;
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  resize() {
    const { clientWidth: w, clientHeight: h } = this.canvas;
    if (!w || !h) return;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestDraw();
  }

  // Loads `url`; resolves to what the file holds: {strands, truth, points,
  // head, animation (its name or null), duration (s)}, or to null when a newer
  // load was asked for meanwhile. Rejects naming the URL when the file cannot
  // be read or is not glTF.
  async load(url) {
    this.clear();
    const token = ++this.loads;
    this.firstFrameAt = null;
    const gltf = await new Promise((resolve, reject) => {
      new GLTFLoader().load(url, resolve, undefined, (err) => {
        const status = err?.target?.status;  // an HTTP error comes as the request's ProgressEvent
        const why = status ? `HTTP ${status} ${err.target.statusText}` : (err?.message ?? String(err));
        reject(new Error(`3D view: ${url.split('?')[0]}: ${why}`));
      });
    });
    if (token !== this.loads) return null;  // superseded: the newer load shows its model
    this.model = gltf.scene;
    this.scene.add(this.model);
    const clip = gltf.animations[0] ?? null;
    this.parts = {
      strands: this.model.getObjectByName('strands') ?? null,
      truth: this.model.getObjectByName('truth') ?? null,
      points: this.model.getObjectByName('points') ?? null,
      head: this.model.getObjectByName('head') ?? null,
      simulation: null,
    };
    // The animated node: named as its clip, its children the frames.
    const animated = clip ? this.model.getObjectByName(clip.name) : null;
    if (animated && animated.children.length > 0) this.parts.simulation = animated;
    this.styleParts();
    if (this.parts.simulation) {
      this.mixer = new THREE.AnimationMixer(this.model);
      this.action = this.mixer.clipAction(clip);
    }
    this.shown = { strands: true, truth: false, points: false, head: true };
    this.applyVisibility();
    this.frame();
    this.requestDraw();
    return {
      strands: !!this.parts.strands, truth: !!this.parts.truth, points: !!this.parts.points,
      head: !!this.parts.head, animation: this.action ? clip.name : null,
      wisps: linesUnder(this.parts.strands).some((l) => l.geometry.attributes._wisp_id),
      duration: this.action ? clip.duration : 0,
    };
  }

  clear() {
    this.pause();
    if (this.model) {
      this.scene.remove(this.model);
      this.model.traverse((o) => {
        o.geometry?.dispose();
        o.material?.dispose?.();
      });
    }
    this.model = null;
    this.parts = {};
    this.coarse = null;
    this.mixer = null;
    this.action = null;
    this.requestDraw();
  }

  // While the camera moves, the coarse strands stand in for the full ones.
  setMoving(moving) {
    this.moving = moving;
    this.applyVisibility();
  }

  // Each object's visibility from what is asked (this.shown), whether the
  // simulation plays (it replaces the strands) and whether the camera moves.
  applyVisibility() {
    const { strands, truth, points, head, simulation } = this.parts;
    const strandsShown = this.shown.strands && !this.playing;
    if (strands) strands.visible = strandsShown && !(this.moving && this.coarse);
    if (this.coarse) this.coarse.visible = strandsShown && this.moving;
    if (simulation) simulation.visible = Boolean(this.playing);
    if (truth) truth.visible = this.shown.truth;
    if (points) points.visible = this.shown.points;
    if (head) head.visible = this.shown.head;
    this.requestDraw();
  }

  styleParts() {
    for (const lines of [...linesUnder(this.parts.strands), ...linesUnder(this.parts.simulation)]) {
      lines.material = new THREE.LineBasicMaterial({ vertexColors: THREE.VertexColors });
    }
    for (const lines of linesUnder(this.parts.truth)) {
      lines.material = new THREE.LineBasicMaterial({ color: 0x39d36b });
    }
    this.parts.points?.traverse((o) => {
      if (o.isPoints) {
        o.material = new THREE.PointsMaterial({ size: 2, sizeAttenuation: false,
                                                vertexColors: THREE.VertexColors });
      }
    });
    const full = linesUnder(this.parts.strands)[0];
    this.coarse = full ? coarseStrands(full, MOVING_STRANDS) : null;
    if (this.coarse) full.parent.add(this.coarse);
    this.setColourBy(this.colourMode);
  }

  // The camera at the strands, truth, points and head (not the animation's
  // frames: those not showing are scaled to 0 at the origin), looking at the front.
  frame() {
    const box = new THREE.Box3();
    for (const part of ['strands', 'truth', 'points', 'head']) {
      if (this.parts[part]) box.expandByObject(this.parts[part]);
    }
    if (box.isEmpty()) return;
    const centre = box.getCenter(new THREE.Vector3());
    const radius = box.getSize(new THREE.Vector3()).length() / 2;
    // Far enough that the model's bounding sphere fits the view's height.
    const distance = radius / Math.tan(THREE.Math.degToRad(this.camera.fov / 2));
    this.camera.near = distance / 100;
    this.camera.far = distance * 10;
    this.camera.position.set(centre.x, centre.y + 0.15 * distance, centre.z + distance);
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
  }

  // `part`: 'strands', 'truth', 'points' or 'head'. False when the model has no such part.
  setVisible(part, visible) {
    if (!this.parts[part]) return false;
    this.shown[part] = visible;
    this.applyVisibility();
    return true;
  }

  // 'direction', 'strand' (each strand its own hue) or 'wisp' (each wisp its own hue).
  setColourBy(mode) {
    this.colourMode = mode;
    for (const lines of [...linesUnder(this.parts.strands), ...linesUnder(this.parts.simulation)]) {
      const colours = new THREE.BufferAttribute(strandColours(lines.geometry, mode), 3);
      lines.geometry.setAttribute('color', colours);
      if (this.coarse?.geometry.attributes.position === lines.geometry.attributes.position)
        this.coarse.geometry.setAttribute('color', colours);
    }
    this.requestDraw();
  }

  // Plays the simulation in a loop, in place of the reconstructed strands.
  play() {
    if (!this.action) return false;
    this.action.reset().play();
    this.clock.start();
    this.playing = true;
    this.applyVisibility();
    return true;
  }

  pause() {
    if (!this.playing) return;
    this.playing = false;
    this.clock.stop();
    this.action?.stop();
    this.applyVisibility();
  }

  // The index of the simulation frame showing, or -1.
  shownFrame() {
    if (!this.parts.simulation || !this.playing) return -1;
    return this.parts.simulation.children.findIndex((c) => c.scale.x > 0);
  }

  requestDraw() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      this.draw();
    });
  }

  draw() {
    if (this.playing && this.mixer) {
      this.mixer.update(this.clock.getDelta());
      // A frame scaled to 0 still costs its vertices: only the shown one is drawn.
      for (const f of this.parts.simulation.children) f.visible = f.scale.x > 0;
      this.requestDraw();
    }
    this.renderer.render(this.scene, this.camera);
    this.framesDrawn += 1;
    if (this.model && this.firstFrameAt === null) this.firstFrameAt = performance.now();
  }

  // Plays the simulation for `ms`, then pauses it; resolves to the frames'
  // intervals (ms) as the browser timed them (none without a simulation).
  // For tests and bench/console_viewer_bench.
  playFor(ms) {
    if (!this.play()) return Promise.resolve([]);
    return new Promise((resolve) => {
      const intervals = [];
      let last = null;
      const started = performance.now();
      const step = (now) => {
        if (last !== null) intervals.push(now - last);
        last = now;
        if (now - started < ms) {
          requestAnimationFrame(step);
        } else {
          this.pause();
          resolve(intervals);
        }
      };
      requestAnimationFrame(step);
    });
  }

  // Turns the camera about the model by `degreesPerFrame` each animation
  // frame for `ms`, as a drag does (the coarse strands while it moves, unless
  // `fullDetail`); resolves to the frames' intervals (ms) as the browser
  // timed them. For tests and bench/console_viewer_bench.
  orbitFor(ms, { degreesPerFrame = 2, fullDetail = false } = {}) {
    if (!fullDetail) this.setMoving(true);
    return new Promise((resolve) => {
      const intervals = [];
      let last = null;
      const started = performance.now();
      const step = (now) => {
        if (last !== null) intervals.push(now - last);
        last = now;
        const offset = this.camera.position.clone().sub(this.controls.target);
        offset.applyAxisAngle(new THREE.Vector3(0, 1, 0), THREE.Math.degToRad(degreesPerFrame));
        this.camera.position.copy(this.controls.target).add(offset);
        this.camera.lookAt(this.controls.target);
        this.draw();
        if (now - started < ms) {
          requestAnimationFrame(step);
        } else {
          this.setMoving(false);
          resolve(intervals);
        }
      };
      requestAnimationFrame(step);
    });
  }
}
