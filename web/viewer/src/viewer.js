// visage report viewer: renders the glb embedded in report.html (base64 in
// <script id="visage-glb">) inside <div id="visage-viewer">. Bundled by esbuild
// into one classic script so the report works offline from file://.
import {
  AnimationMixer,
  Box3,
  Color,
  DirectionalLight,
  HemisphereLight,
  LoopRepeat,
  MathUtils,
  PerspectiveCamera,
  Scene,
  SRGBColorSpace,
  Vector3,
  WebGLRenderer,
} from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const ASPECT = 4 / 3;
const MAX_WIDTH = 720;
const FOV = 30; // degrees, vertical; narrow lens = little perspective distortion on a face

// Created synchronously so a test (or the page) can await `ready` even before
// DOMContentLoaded. `duration` and `canvas` are filled in on load.
let resolveReady;
let rejectReady;
const api = {
  ready: new Promise((res, rej) => {
    resolveReady = res;
    rejectReady = rej;
  }),
  duration: 0,
  canvas: null,
  setTime: () => {
    throw new Error('visage viewer not ready');
  },
};
// The failure is already shown in the page and on the console; this only stops
// an extra "Uncaught (in promise)" when nobody awaits `ready`.
api.ready.catch(() => {});
window.visageViewer = api;

function fail(container, err) {
  console.error('visage viewer:', err);
  if (container) {
    const msg = document.createElement('p');
    msg.style.cssText = 'color:#b00020;font:14px/1.4 sans-serif;margin:8px 0';
    msg.textContent = `3-D viewer error: ${err && err.message ? err.message : err}`;
    container.replaceChildren(msg); // drop the empty canvas and controls
  }
  rejectReady(err instanceof Error ? err : new Error(String(err)));
}

function decodeBase64(text) {
  const bin = atob(text.replace(/\s+/g, ''));
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}

// Union of the scene's bounding boxes over the clip, so head motion stays in frame.
function animatedBounds(scene, mixer, duration) {
  const box = new Box3();
  const steps = duration > 0 ? 8 : 1;
  for (let i = 0; i < steps; i++) {
    if (mixer) mixer.setTime((duration * i) / steps);
    scene.updateMatrixWorld(true);
    box.union(new Box3().setFromObject(scene));
  }
  if (mixer) mixer.setTime(0);
  return box;
}

function makeControls(container) {
  const bar = document.createElement('div');
  bar.style.cssText =
    'display:flex;align-items:center;gap:8px;margin-top:6px;font:13px sans-serif';
  const button = document.createElement('button');
  button.type = 'button';
  button.style.minWidth = '4.5em';
  const slider = document.createElement('input');
  slider.type = 'range';
  slider.min = '0';
  slider.step = 'any';
  slider.style.flex = '1';
  slider.setAttribute('aria-label', 'Animation time');
  const label = document.createElement('span');
  label.style.cssText = 'font-variant-numeric:tabular-nums;min-width:9em;text-align:right';
  bar.append(button, slider, label);
  container.appendChild(bar);
  return { bar, button, slider, label };
}

function start(gltf, canvasBox, renderer) {
  // gltf.scene is a Group; only a real Scene honours `background`.
  const scene = new Scene();
  scene.add(gltf.scene);
  scene.background = new Color(0xd9d9d9);
  scene.add(new HemisphereLight(0xffffff, 0x50505a, 1.6));
  const sun = new DirectionalLight(0xffffff, 2.2);
  sun.position.set(0.5, 0.8, 1.0); // upper-right-front: shading shows the face's relief
  scene.add(sun);

  // Meshes without normals would render black under lights.
  scene.traverse((o) => {
    if (o.isMesh && !o.geometry.getAttribute('normal')) o.geometry.computeVertexNormals();
  });

  const clip = gltf.animations[0] || null;
  const duration = clip ? clip.duration : 0;
  const mixer = clip ? new AnimationMixer(scene) : null;
  const action = mixer ? mixer.clipAction(clip).setLoop(LoopRepeat, Infinity).play() : null;

  // Frame the animated bounds from +z (glTF: y up, face looks towards +z).
  const box = animatedBounds(gltf.scene, mixer, duration);
  if (box.isEmpty()) throw new Error('the glTF scene has no geometry');
  const centre = box.getCenter(new Vector3());
  const size = box.getSize(new Vector3());
  const halfFov = MathUtils.degToRad(FOV / 2);
  const fitH = size.y / 2 / Math.tan(halfFov);
  const fitW = size.x / 2 / (Math.tan(halfFov) * ASPECT);
  const dist = 1.25 * Math.max(fitH, fitW) + size.z / 2;
  const span = Math.max(size.x, size.y, size.z);
  const camera = new PerspectiveCamera(FOV, ASPECT, dist / 100, dist + 10 * span);
  camera.position.set(centre.x, centre.y, centre.z + dist);

  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  const ui = makeControls(canvasBox);
  ui.slider.max = String(duration);
  if (!clip) ui.bar.style.display = 'none';

  let playing = !!clip;
  let dirty = true;
  let last = performance.now();

  const render = () => {
    renderer.render(scene, camera);
    dirty = false;
  };
  const showTime = () => {
    const t = action ? action.time : 0; // wrapped into [0, duration)
    ui.slider.value = String(t);
    ui.label.textContent = `${t.toFixed(2)} s / ${duration.toFixed(2)} s`;
    ui.button.textContent = playing ? 'Pause' : 'Play';
  };
  const setTime = (t) => {
    playing = false;
    // Just below duration: LoopRepeat would wrap exactly `duration` back to 0.
    if (mixer) mixer.setTime(Math.min(Math.max(Number(t) || 0, 0), duration * 0.9999));
    showTime();
    render(); // synchronous, so a caller can read pixels right after
  };

  ui.button.addEventListener('click', () => {
    playing = !playing;
    showTime();
  });
  ui.slider.addEventListener('input', () => setTime(parseFloat(ui.slider.value)));
  controls.addEventListener('change', () => {
    dirty = true;
  });

  const resize = () => {
    const w = Math.max(1, Math.floor(canvasBox.clientWidth));
    renderer.setSize(w, Math.round(w / ASPECT), false);
    dirty = true;
  };
  new ResizeObserver(resize).observe(canvasBox);
  resize();

  // Render on demand (playing, orbiting, resizing): software GL is slow and
  // an idle report should not spin a CPU core.
  const loop = (now) => {
    if (playing && mixer) {
      // Clamped: no jump after a hidden tab, no negative step from rAF timestamps.
      mixer.update(Math.min(Math.max((now - last) / 1000, 0), 0.1));
      showTime();
      dirty = true;
    }
    last = now;
    if (dirty) render();
    requestAnimationFrame(loop);
  };

  if (mixer) mixer.setTime(0);
  showTime();
  render();
  requestAnimationFrame(loop);

  api.duration = duration;
  api.setTime = setTime;
  resolveReady(api);
}

function init() {
  const container = document.getElementById('visage-viewer');
  try {
    if (!container) throw new Error('no element #visage-viewer in the page');
    const data = document.getElementById('visage-glb');
    if (!data) throw new Error('no <script id="visage-glb"> with the model in the page');
    const buffer = decodeBase64(data.textContent);

    // Canvas + controls box: full width up to MAX_WIDTH; the canvas keeps 4:3
    // through its width/height attributes with height:auto.
    const canvasBox = document.createElement('div');
    canvasBox.style.cssText = `width:100%;max-width:${MAX_WIDTH}px`;
    container.appendChild(canvasBox);
    const renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.outputColorSpace = SRGBColorSpace;
    renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    renderer.domElement.style.cssText = 'display:block;width:100%;height:auto';
    canvasBox.appendChild(renderer.domElement);
    api.canvas = renderer.domElement;

    new GLTFLoader().parse(
      buffer,
      '',
      (gltf) => {
        try {
          start(gltf, canvasBox, renderer);
        } catch (err) {
          fail(container, err);
        }
      },
      (err) => fail(container, err),
    );
  } catch (err) {
    fail(container, err);
  }
}

if (document.readyState === 'loading') {
  document.addEventListener('DOMContentLoaded', init);
} else {
  init();
}
