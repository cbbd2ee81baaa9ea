// The page liveprobe --serve shows: a model lit by a three.js LightProbe (and a DirectionalLight
// per light) that every message of the stream updates, with the message rate and the
// coefficients. Messages are liveprobe's frame records in the `three` format (README: Lighting
// your engine). ?freeze=1 keeps the first frame (the browser test compares pixels with it).
import * as THREE from 'three';

const params = new URLSearchParams(location.search);
const freeze = params.has('freeze');

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(innerWidth, innerHeight);
renderer.toneMapping = THREE.NoToneMapping;  // the pixel is albedo * E / pi, sRGB-encoded
document.body.appendChild(renderer.domElement);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(35, innerWidth / innerHeight, 0.1, 100);
camera.position.set(0, 0, 6);
camera.lookAt(0, 0, 0);

const white = new THREE.MeshLambertMaterial({ color: 0xffffff });
const sphere = new THREE.Mesh(new THREE.SphereGeometry(1, 96, 48), white);
scene.add(sphere);
const knot = new THREE.Mesh(new THREE.TorusKnotGeometry(0.45, 0.15, 160, 24), white);
knot.position.set(1.9, 0, 0);
scene.add(knot);
const knot2 = knot.clone();
knot2.position.set(-1.9, 0, 0);
scene.add(knot2);

const probe = new THREE.LightProbe();
scene.add(probe);
const suns = [];

let exposure = 0, frames = 0, last = null, rateT0 = performance.now(), rateN = 0;
const state = document.getElementById('state');
const status = document.getElementById('status');

/// 1 / the largest E / pi over the sphere: the brightest white surface shows at 1.
function autoExposure(sh, lights) {
  const n = new THREE.Vector3(), e = new THREE.Vector3();
  let max = 1e-9;
  for (let i = 0; i < 256; ++i) {
    const z = 1 - (2 * i + 1) / 256, r = Math.sqrt(1 - z * z), p = i * 2.399963;
    n.set(r * Math.cos(p), z, r * Math.sin(p));
    sh.getIrradianceAt(n, e);
    for (const l of lights) {
      const c = Math.max(0, n.dot(new THREE.Vector3(...l.direction))) * l.intensity;
      e.x += c * l.color[0], e.y += c * l.color[1], e.z += c * l.color[2];
    }
    max = Math.max(max, e.x, e.y, e.z);
  }
  return Math.PI / max;
}

function apply(msg) {
  const c = msg.coefficients;
  probe.sh.fromArray(c.sh);
  if (!exposure) exposure = autoExposure(probe.sh, c.directionalLights || []);
  probe.intensity = c.intensity * exposure;
  const lights = c.directionalLights || [];
  while (suns.length < lights.length) {
    const l = new THREE.DirectionalLight();
    scene.add(l, l.target);
    suns.push(l);
  }
  suns.forEach((l, i) => {
    l.visible = i < lights.length;
    if (!l.visible) return;
    l.position.set(...lights[i].direction).multiplyScalar(10);
    l.color.setRGB(...lights[i].color, THREE.LinearSRGBColorSpace);
    l.intensity = lights[i].intensity * exposure;
  });
  const rows = [];
  const names = ['L00', 'L1-1', 'L10', 'L11', 'L2-2', 'L2-1', 'L20', 'L21', 'L22'];
  for (let k = 0; k < 9; ++k)
    rows.push(`<tr><td>${names[k]}</td>${[0, 1, 2].map((ch) => `<td>${c.sh[3 * k + ch].toFixed(4)}</td>`).join('')}</tr>`);
  document.getElementById('coeffs').innerHTML = rows.join('');
}

function connect() {
  const ws = new WebSocket(`ws://${location.host}/?format=three`);
  ws.onopen = () => { status.textContent = 'connected'; status.className = ''; };
  ws.onmessage = (ev) => {
    const msg = JSON.parse(ev.data);
    ++frames, ++rateN;
    if (!(freeze && last)) { last = msg; apply(msg); }
    // What the page shows, for tests: the frame drawn and how many messages came.
    state.textContent = JSON.stringify({ frame: last.frame, exposure, coefficients: last.coefficients, frames });
  };
  ws.onclose = (ev) => {
    status.textContent = `disconnected (${ev.code}${ev.reason ? ': ' + ev.reason : ''}); retrying`;
    status.className = 'bad';
    setTimeout(connect, 1000);
  };
}
connect();

addEventListener('resize', () => {
  renderer.setSize(innerWidth, innerHeight);
  camera.aspect = innerWidth / innerHeight;
  camera.updateProjectionMatrix();
});

renderer.setAnimationLoop(() => {
  const now = performance.now();
  if (now - rateT0 > 1000) {
    document.getElementById('rate').textContent =
        `frame ${last ? last.frame : '-'}, ${(1000 * rateN / (now - rateT0)).toFixed(1)} messages/s`;
    rateT0 = now, rateN = 0;
  }
  if (!freeze) knot.rotation.y = knot2.rotation.y = now / 2000;
  renderer.render(scene, camera);
});
