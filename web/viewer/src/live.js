// visage live page: the face mesh, head motion and a few ARKit curves of a `visage live`
// session, as they arrive over the page's own WebSocket. Bundled by esbuild into one classic
// script (dist/live.js) that the visage binary serves as /live.js.
//
// Messages (see crates/visage/src/live/live_page.rs):
// - text: {"type":"mesh","vertices":V,"triangles":[...],"weights":[52 names]} before the first
//   frame of a mesh;
// - binary: little-endian float32s: frame index, session seconds, latency ms, fps, has face,
//   head yaw, pitch, roll (radians), the 52 weights, then V × (x, y, z) metres in camera
//   coordinates (x right, y down, z forward).
import {
  BufferAttribute,
  BufferGeometry,
  Color,
  DirectionalLight,
  DoubleSide,
  HemisphereLight,
  Mesh,
  MeshStandardMaterial,
  PerspectiveCamera,
  Scene,
  SRGBColorSpace,
  Vector3,
  WebGLRenderer,
} from 'three';

const HEADER = 8 + 52;
const ASPECT = 4 / 3;
const FOV = 30;
const HISTORY = 300; // frames of curves kept (10 s at 30 fps)
const CURVES = [
  ['jawOpen', '#d62728'],
  ['eyeBlinkLeft', '#1f77b4'],
  ['eyeBlinkRight', '#17becf'],
  ['mouthSmileLeft', '#2ca02c'],
  ['mouthSmileRight', '#98df8a'],
  ['browInnerUp', '#9467bd'],
];

const state = {
  frames: 0,
  fps: 0,
  latencyMs: 0,
  index: -1,
  face: false,
  connected: false,
  closed: false,
  snapshot: () => [],
};
window.visageLive = state;

function problem(text) {
  const p = document.getElementById('problem');
  p.textContent = text;
  p.hidden = false;
}

function init() {
  const box = document.getElementById('face');
  const stats = document.getElementById('stats');
  const curvesCanvas = document.getElementById('curves');
  const renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.outputColorSpace = SRGBColorSpace;
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  box.appendChild(renderer.domElement);
  const resize = () => {
    const w = Math.max(1, Math.floor(box.clientWidth));
    renderer.setSize(w, Math.round(w / ASPECT), false);
    dirty = true;
  };

  const scene = new Scene();
  scene.background = new Color(0xd9d9d9);
  scene.add(new HemisphereLight(0xffffff, 0x50505a, 1.6));
  const sun = new DirectionalLight(0xffffff, 2.2);
  sun.position.set(0.5, 0.8, 1.0);
  scene.add(sun);
  const camera = new PerspectiveCamera(FOV, ASPECT, 0.01, 20);
  const material = new MeshStandardMaterial({ color: 0xe0b8a0, roughness: 0.7, side: DoubleSide });
  let mesh = null;
  let names = [];
  let framed = false;
  let dirty = true;
  const history = CURVES.map(() => []);

  new ResizeObserver(resize).observe(box);
  resize();

  // A small grey-level picture of the face's canvas, for tests to compare two moments.
  state.snapshot = () => {
    const c = document.createElement('canvas');
    c.width = 64;
    c.height = 48;
    const g = c.getContext('2d');
    g.drawImage(renderer.domElement, 0, 0, 64, 48);
    const d = g.getImageData(0, 0, 64, 48).data;
    const out = [];
    for (let i = 0; i < d.length; i += 4) out.push((d[i] + d[i + 1] + d[i + 2]) / 3);
    return out;
  };

  function setTopology(message) {
    if (mesh) {
      scene.remove(mesh);
      mesh.geometry.dispose();
    }
    const geometry = new BufferGeometry();
    geometry.setAttribute('position', new BufferAttribute(new Float32Array(message.vertices * 3), 3));
    geometry.setIndex(message.triangles);
    mesh = new Mesh(geometry, material);
    mesh.visible = false;
    scene.add(mesh);
    names = message.weights || [];
    framed = false;
  }

  function onFrame(buffer) {
    const f = new Float32Array(buffer);
    if (f.length < HEADER) return;
    state.frames += 1;
    state.index = f[0];
    state.latencyMs = f[2];
    state.fps = f[3];
    state.face = f[4] > 0.5;
    const weights = f.subarray(8, HEADER);
    CURVES.forEach(([name], k) => {
      const i = names.indexOf(name);
      history[k].push(i >= 0 && state.face ? weights[i] : NaN);
      if (history[k].length > HISTORY) history[k].shift();
    });
    const head = [f[5], f[6], f[7]].map((r) => ((r * 180) / Math.PI).toFixed(0));
    stats.textContent =
      `${state.fps.toFixed(1)} fps · latency ${state.latencyMs.toFixed(0)} ms · frame ${state.index}` +
      (state.face ? ` · head yaw ${head[0]}°, pitch ${head[1]}°, roll ${head[2]}°` : ' · no face');
    if (mesh && state.face && f.length > HEADER) {
      const position = mesh.geometry.getAttribute('position');
      const v = position.array;
      const n = Math.min(v.length, f.length - HEADER);
      // Camera coordinates (y down, z forward) to three.js's (y up, z towards the viewer).
      for (let i = 0; i < n; i += 3) {
        v[i] = f[HEADER + i];
        v[i + 1] = -f[HEADER + i + 1];
        v[i + 2] = -f[HEADER + i + 2];
      }
      position.needsUpdate = true;
      mesh.geometry.computeVertexNormals();
      mesh.geometry.computeBoundingSphere();
      mesh.visible = true;
      if (!framed) {
        // Aim at where the face first appears; later motion then shows as motion.
        const s = mesh.geometry.boundingSphere;
        camera.position.set(0, 0, 0);
        camera.lookAt(s.center);
        const distance = s.center.length();
        const needed = (2.6 * s.radius) / (2 * Math.tan((FOV * Math.PI) / 360));
        camera.position.copy(s.center.clone().multiplyScalar(1 - needed / Math.max(distance, 1e-6)));
        camera.lookAt(s.center);
        camera.up.set(0, 1, 0);
        camera.updateProjectionMatrix();
        framed = true;
      }
    } else if (mesh) {
      mesh.visible = false;
    }
    dirty = true;
  }

  function drawCurves() {
    const g = curvesCanvas.getContext('2d');
    const w = curvesCanvas.width;
    const h = curvesCanvas.height;
    const legend = 130;
    const plotW = w - legend - 30;
    g.clearRect(0, 0, w, h);
    g.strokeStyle = '#ddd';
    g.fillStyle = '#666';
    g.font = '11px sans-serif';
    for (const y of [0, 0.5, 1]) {
      const py = 10 + (1 - y) * (h - 20);
      g.beginPath();
      g.moveTo(30, py);
      g.lineTo(30 + plotW, py);
      g.stroke();
      g.fillText(y.toFixed(1), 4, py + 4);
    }
    CURVES.forEach(([name, colour], k) => {
      g.strokeStyle = colour;
      g.lineWidth = 1.5;
      g.beginPath();
      let pen = false;
      const n = history[k].length;
      history[k].forEach((v, i) => {
        // The newest sample at the right edge.
        const x = 30 + plotW - ((n - 1 - i) / (HISTORY - 1)) * plotW;
        const y = 10 + (1 - v) * (h - 20);
        if (Number.isNaN(v)) pen = false;
        else if (pen) g.lineTo(x, y);
        else {
          g.moveTo(x, y);
          pen = true;
        }
      });
      g.stroke();
      g.fillStyle = colour;
      g.fillRect(w - legend + 6, 14 + k * 18, 12, 3);
      g.fillStyle = '#333';
      g.fillText(name, w - legend + 22, 19 + k * 18);
    });
  }

  const loop = () => {
    if (dirty) {
      renderer.render(scene, camera);
      drawCurves();
      dirty = false;
    }
    requestAnimationFrame(loop);
  };
  camera.position.set(0, 0, 0);
  camera.lookAt(new Vector3(0, 0, -1));
  requestAnimationFrame(loop);

  const socket = new WebSocket(`ws://${location.host}/socket`);
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => {
    state.connected = true;
    stats.textContent = 'connected, waiting for frames…';
  };
  socket.onmessage = (event) => {
    if (typeof event.data === 'string') {
      const message = JSON.parse(event.data);
      if (message.type === 'mesh') setTopology(message);
    } else {
      onFrame(event.data);
    }
  };
  socket.onclose = () => {
    state.connected = false;
    state.closed = true;
    stats.textContent += ' · the session ended';
  };
  socket.onerror = () => problem('The connection to visage live failed (is it still running?).');
}

if (document.readyState === 'loading') {
  document.addEventListener('DOMContentLoaded', init);
} else {
  init();
}
