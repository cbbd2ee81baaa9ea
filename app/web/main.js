// The page liveprobe --serve shows, lit as an engine user would light a scene with the stream:
// the coefficients as a three.js LightProbe, each light (--sun) as a DirectionalLight, the first
// casting its shadow on a ground, all updated by every message; beside it the message rate, a
// plot of the light over time and the coefficients. Messages are liveprobe's frame records in the
// `three` format (docs/engines.md). ?freeze=1 keeps the first frame (the browser test compares
// pixels with it).
import * as THREE from 'three';

const params = new URLSearchParams(location.search);
const freeze = params.has('freeze');

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(innerWidth, innerHeight);
renderer.toneMapping = THREE.NoToneMapping;  // the pixel is albedo * E / pi, sRGB-encoded
renderer.shadowMap.enabled = true;
renderer.shadowMap.type = THREE.PCFShadowMap;  // filtered (three.js r187 has no "soft" one)
document.body.appendChild(renderer.domElement);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(35, innerWidth / innerHeight, 0.1, 100);
camera.position.set(0, 0, 7);
camera.lookAt(0, 0, 0);

// A white sphere (its centre faces the camera: the browser test reads it) and a knot stand on a
// grey ground that catches the sun's shadow. The sphere casts but does not receive shadows, so
// its centre is always lit by the probe and the sun in full.
const white = new THREE.MeshLambertMaterial({ color: 0xffffff });
const sphere = new THREE.Mesh(new THREE.SphereGeometry(1, 96, 48), white);
sphere.castShadow = true;
scene.add(sphere);
const knot = new THREE.Mesh(new THREE.TorusKnotGeometry(0.5, 0.17, 160, 24), white);
knot.position.set(-2.2, -0.25, -0.6);
knot.castShadow = knot.receiveShadow = true;
scene.add(knot);
const ground = new THREE.Mesh(new THREE.PlaneGeometry(40, 40),
                              new THREE.MeshLambertMaterial({ color: 0x808080 }));
ground.rotation.x = -Math.PI / 2;
ground.position.y = -1;
ground.receiveShadow = true;
scene.add(ground);

const probe = new THREE.LightProbe();
scene.add(probe);

// Behind the scene, the probe's own light: the radiance its nine coefficients hold in each
// direction (three's SphericalHarmonics3.getAt, per pixel), the low-frequency sky the model is
// lit by, at the same exposure. The sun, taken out as a light, is not in it.
const skyUniforms = { sh: { value: Array.from({ length: 9 }, () => new THREE.Vector3()) },
                      scale: { value: 0 } };
const sky = new THREE.Mesh(new THREE.SphereGeometry(50, 64, 32), new THREE.ShaderMaterial({
  side: THREE.BackSide, depthWrite: false, uniforms: skyUniforms,
  vertexShader: `varying vec3 vDir;
    void main() { vDir = normalize(position); gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }`,
  fragmentShader: `uniform vec3 sh[9]; uniform float scale; varying vec3 vDir;
    void main() {
      vec3 n = normalize(vDir);
      vec3 c = sh[0] * 0.282095 + sh[1] * 0.488603 * n.y + sh[2] * 0.488603 * n.z + sh[3] * 0.488603 * n.x
             + sh[4] * 1.092548 * n.x * n.y + sh[5] * 1.092548 * n.y * n.z + sh[6] * 0.315392 * (3.0 * n.z * n.z - 1.0)
             + sh[7] * 1.092548 * n.x * n.z + sh[8] * 0.546274 * (n.x * n.x - n.y * n.y);
      gl_FragColor = vec4(max(c * scale, 0.0), 1.0);
      #include <colorspace_fragment>
    }`,
}));
scene.add(sky);
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
  probe.sh.coefficients.forEach((v, k) => skyUniforms.sh.value[k].copy(v));
  skyUniforms.scale.value = probe.intensity;
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
    if (i === 0 && !l.castShadow) {  // the first light's shadow: a box around the objects
      l.castShadow = true;
      l.shadow.mapSize.set(2048, 2048);
      Object.assign(l.shadow.camera, { left: -6, right: 6, top: 6, bottom: -6, near: 0.5, far: 30 });
      l.shadow.camera.updateProjectionMatrix();
      l.shadow.radius = 3;
    }
    l.color.setRGB(...lights[i].color, THREE.LinearSRGBColorSpace);
    l.intensity = lights[i].intensity * exposure;
  });
  const rows = [];
  const names = ['L00', 'L1-1', 'L10', 'L11', 'L2-2', 'L2-1', 'L20', 'L21', 'L22'];
  for (let k = 0; k < 9; ++k)
    rows.push(`<tr><td>${names[k]}</td>${[0, 1, 2].map((ch) => `<td>${c.sh[3 * k + ch].toFixed(4)}</td>`).join('')}</tr>`);
  document.getElementById('coeffs').innerHTML = rows.join('');
  past.push([lum(c.sh, 0), Math.hypot(...[1, 2, 3].map((k) => lum(c.sh, k))),
                Math.hypot(...[4, 5, 6, 7, 8].map((k) => lum(c.sh, k))),
                lights.reduce((s, l) => s + l.intensity * lum(l.color, 0), 0)]);
  if (past.length > kHistory) past.shift();
  drawPlot();
}

// The light over time: L00, the norms of bands 1 and 2 (luminance), and the lights' intensity.
const kHistory = 150, past = [];
const lum = (v, k) => 0.2126 * v[3 * k] + 0.7152 * v[3 * k + 1] + 0.0722 * v[3 * k + 2];
const series = [['L00', '#f2c14e'], ['band 1', '#6fb3f2'], ['band 2', '#9be39b'], ['sun', '#f28b82']];
function drawPlot() {
  const plot = document.getElementById('plot'), g = plot.getContext('2d');
  const w = plot.width, h = plot.height, top = 12;
  g.clearRect(0, 0, w, h);
  g.fillStyle = 'rgba(20, 20, 24, 0.8)';
  g.fillRect(0, top, w, h - top);
  const max = Math.max(1e-9, ...past.flat());
  series.forEach(([name, colour], s) => {
    g.strokeStyle = g.fillStyle = colour;
    g.fillText(name, 2 + 46 * s, 9);
    g.beginPath();
    past.forEach((v, i) => {
      const x = w - 1 - (past.length - 1 - i) * (w - 2) / (kHistory - 1);
      const y = h - 2 - (h - top - 4) * v[s] / max;
      i ? g.lineTo(x, y) : g.moveTo(x, y);
    });
    g.stroke();
  });
}

/// Where the sphere's centre casts its shadow on the ground, and a ground point beside it that
/// the sun lights, in canvas pixels (for tests): null when the sun is too low for it to show, or
/// the shadow falls off the canvas.
function shadowPoints(c) {
  const l = (c.directionalLights || [])[0];
  if (!l || l.direction[1] < 0.2) return null;
  const d = new THREE.Vector3(...l.direction);
  const inShadow = d.clone().multiplyScalar(-1 / d.y);  // from (0, 0, 0) away from the sun to y = -1
  const px = (p) => {
    const v = p.clone().project(camera);
    return [Math.round((v.x + 1) / 2 * innerWidth), Math.round((1 - v.y) / 2 * innerHeight)];
  };
  const onCanvas = ([x, y]) => x >= 0 && x < innerWidth && y >= 0 && y < innerHeight;
  // The lit point 2.5 units beside the shadow, on whichever side is still on the canvas.
  const lit = [[0, 2.5], [2.5, 0], [-2.5, 0], [0, -2.5]]
                  .map(([x, z]) => px(inShadow.clone().add(new THREE.Vector3(x, 0, z))))
                  .find(onCanvas);
  return onCanvas(px(inShadow)) && lit ? { inShadow: px(inShadow), lit } : null;
}

function connect() {
  const ws = new WebSocket(`ws://${location.host}/?format=three`);
  ws.onopen = () => { status.textContent = 'connected'; status.className = ''; };
  ws.onmessage = (ev) => {
    const msg = JSON.parse(ev.data);
    ++frames, ++rateN;
    if (!(freeze && last)) { last = msg; apply(msg); }
    // What the page shows, for tests: the frame drawn and how many messages came.
    state.textContent = JSON.stringify({ frame: last.frame, exposure, coefficients: last.coefficients, frames,
                                         shadow: shadowPoints(last.coefficients) });
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
  if (!freeze) knot.rotation.y = now / 2000;
  renderer.render(scene, camera);
});
