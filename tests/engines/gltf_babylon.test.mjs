// The glTF export's specular cube through Babylon.js's own glTF loader (npm @babylonjs/loaders,
// its EXT_lights_image_based extension) in Debian's chromium, headless (WebGL on SwiftShader):
// the cube Babylon builds from the face images, projected by Babylon's own
// CubeMapToSphericalPolynomialTools, is the light of the exported irradianceCoefficients (the
// polynomial the same loader makes of them). A cube stored upside down fails it. And where
// Babylon puts the document's light in a scene of either handedness, with and without the
// lines docs/engines.md gives.
import { after, test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { data, maps, run } from './common.mjs';
import { harmonicsFunctions } from './babylon_shader.mjs';
import { SphericalHarmonics } from '@babylonjs/core/Maths/sphericalPolynomial.js';

const modules = join(dirname(fileURLToPath(import.meta.url)), 'node_modules');
const page = `<!doctype html><body></body>
<script type="importmap">{"imports": {"@babylonjs/core/": "/node_modules/@babylonjs/core/",
  "@babylonjs/loaders/": "/node_modules/@babylonjs/loaders/"}}</script>
<script type="module">
import { Engine } from '@babylonjs/core/Engines/engine.js';
import { Scene } from '@babylonjs/core/scene.js';
import { AppendSceneAsync } from '@babylonjs/core/Loading/sceneLoader.js';
import { CubeMapToSphericalPolynomialTools } from '@babylonjs/core/Misc/HighDynamicRange/cubemapToSphericalPolynomial.js';
import { SphericalHarmonics, SphericalPolynomial } from '@babylonjs/core/Maths/sphericalPolynomial.js';
import '@babylonjs/core/Engines/Extensions/engine.readTexture.js';
import '@babylonjs/core/Loading/loadingScreen.js';
import '@babylonjs/core/Materials/Textures/baseTexture.polynomial.js';
import '@babylonjs/loaders/glTF/2.0/index.js';
import { FreeCamera } from '@babylonjs/core/Cameras/freeCamera.js';
import { Camera } from '@babylonjs/core/Cameras/camera.js';
import { Matrix, Vector3 } from '@babylonjs/core/Maths/math.vector.js';
import { Color3, Color4 } from '@babylonjs/core/Maths/math.color.js';
import { CreateSphere } from '@babylonjs/core/Meshes/Builders/sphereBuilder.js';
import { PBRMaterial } from '@babylonjs/core/Materials/PBR/pbrMaterial.js';
import { ShaderMaterial } from '@babylonjs/core/Materials/shaderMaterial.js';
// Each call draws on a canvas of its own: one page serves every test of the file.
const freshCanvas = (size) => {
  const canvas = document.createElement('canvas');
  canvas.width = canvas.height = size;
  document.body.replaceChildren(canvas);
  return canvas;
};
// A white diffuse sphere lit by the document's light alone, seen from above (world +y) by an
// orthographic camera; then the same pixels' world normals (a second pass that draws them).
window.shade = async (rightHanded, size, albedo, fixed) => {
  const canvas = freshCanvas(size);
  const engine = new Engine(canvas, false, { preserveDrawingBuffer: true });
  const scene = new Scene(engine);
  scene.useRightHandedSystem = rightHanded;
  scene.clearColor = new Color4(0, 0, 0, 0);
  await AppendSceneAsync('/model.gltf', scene);
  const texture = scene.environmentTexture;
  for (let i = 0; i < 1000 && !(texture && texture.isReady()); ++i) await new Promise((r) => setTimeout(r, 20));
  if (fixed) {  // docs/engines.md: the environment in the glTF frame, its intensity once
    texture.invertZ = true;
    if (!rightHanded) Matrix.RotationYToRef(Math.PI, texture.getReflectionTextureMatrix());
    const light = texture.sphericalPolynomial;  // the polynomial's form and the shader's both
    light.preScaledHarmonics.scaleInPlace(1 / texture.level);
    light.scaleInPlace(1 / texture.level);
  }
  const camera = new FreeCamera('above', new Vector3(0, 5, 0), scene);
  camera.upVector = new Vector3(0, 0, 1);
  camera.setTarget(Vector3.Zero());
  camera.mode = Camera.ORTHOGRAPHIC_CAMERA;
  camera.orthoLeft = camera.orthoBottom = -1.05;
  camera.orthoRight = camera.orthoTop = 1.05;
  const sphere = CreateSphere('sphere', { diameter: 2, segments: 96 }, scene);
  const lit = new PBRMaterial('lit', scene);
  lit.albedoColor = new Color3(albedo, albedo, albedo);  // no channel beyond 8 bits
  lit.metallic = 0;
  lit.roughness = 1;
  lit.metallicF0Factor = 0;  // no specular: the polynomial's diffuse alone
  const normals = new ShaderMaterial('normals', scene, {
    vertexSource: 'precision highp float; attribute vec3 position; attribute vec3 normal;' +
      'uniform mat4 world; uniform mat4 worldViewProjection; varying vec3 vN; void main() {' +
      'vN = (world * vec4(normal, 0.0)).xyz; gl_Position = worldViewProjection * vec4(position, 1.0); }',
    fragmentSource: 'precision highp float; varying vec3 vN;' +
      'void main() { gl_FragColor = vec4(normalize(vN) * 0.5 + 0.5, 1.0); }',
  }, { attributes: ['position', 'normal'], uniforms: ['world', 'worldViewProjection'] });
  const draw = async (material) => {
    sphere.material = material;
    await scene.whenReadyAsync();
    // Shaders compile in parallel: draw until the material has drawn the sphere.
    for (let i = 0; i < 200 && !material.isReady(sphere); ++i) {
      scene.render();
      await new Promise((r) => setTimeout(r, 20));
    }
    scene.render();
    return Array.from(await engine.readPixels(0, 0, size, size));
  };
  const shaded = await draw(lit);
  const normal = await draw(normals);
  engine.dispose();
  return { shaded, normal };
};
window.project = async (gltf) => {
  const engine = new Engine(freshCanvas(64));
  const scene = new Scene(engine);
  await AppendSceneAsync('/model.gltf', scene);
  const texture = scene.environmentTexture;
  await new Promise((resolve) => scene.executeWhenReady(resolve));
  for (let i = 0; i < 1000 && !texture.isReady(); ++i) await new Promise((r) => setTimeout(r, 20));
  const keys = ['x', 'y', 'z', 'xx', 'yy', 'zz', 'yz', 'zx', 'xy'];
  const asObject = (p) => Object.fromEntries(keys.map((k) => [k, p[k].asArray()]));
  // The loader's RGBD pass has expanded the faces to linear half floats (texture type 2, not
  // RGBD any more), but the texture keeps RawCubeTexture's default gammaSpace, which would make
  // the projection raise them to the power 2.2: they are linear.
  const info = 'type ' + texture._texture.type + ', RGBD ' + texture.isRGBD;
  texture.gammaSpace = false;
  const cube = await CubeMapToSphericalPolynomialTools.ConvertCubeMapTextureToSphericalPolynomial(texture);
  // The coefficients' polynomial, made as the loader makes it (EXT_lights_image_based).
  const light = gltf.extensions.EXT_lights_image_based.lights[0];
  const sh = SphericalHarmonics.FromArray(light.irradianceCoefficients);
  sh.scaleInPlace(light.intensity);
  sh.convertIrradianceToLambertianRadiance();
  const fromCoefficients = SphericalPolynomial.FromHarmonics(sh);
  cube.scaleInPlace(texture.level);  // the light's intensity, which the shaders multiply in
  const result = { cube: asObject(cube), coefficients: asObject(fromCoefficients), info };
  engine.dispose();
  return result;
};
window.ready = true;
</script>`;

/// n directions spread evenly over the sphere.
function fibonacciSphere(n) {
  return Array.from({ length: n }, (_, i) => {
    const z = 1 - (2 * i + 1) / n, s = Math.sqrt(1 - z * z), p = i * Math.PI * (3 - Math.sqrt(5));
    return [s * Math.cos(p), s * Math.sin(p), z];
  });
}

/// Pearson correlation of two equal-length arrays.
function correlation(a, b) {
  const n = a.length, ma = a.reduce((s, v) => s + v, 0) / n, mb = b.reduce((s, v) => s + v, 0) / n;
  let ab = 0, aa = 0, bb = 0;
  for (let i = 0; i < n; ++i) {
    ab += (a[i] - ma) * (b[i] - mb);
    aa += (a[i] - ma) ** 2;
    bb += (b[i] - mb) ** 2;
  }
  return ab / Math.sqrt(aa * bb);
}

function evalPolynomial(p, [x, y, z]) {
  const m = { x, y, z, xx: x * x, yy: y * y, zz: z * z, yz: y * z, zx: z * x, xy: x * y };
  return [0, 1, 2].map((ch) => Object.keys(m).reduce((s, k) => s + p[k][ch] * m[k], 0));
}

const types = { '.js': 'text/javascript', '.html': 'text/html', '.gltf': 'model/gltf+json' };

// One browser and one page for the whole file (Babylon's modules load once: a launch and a load
// took 4 to 7 s of each test); `/model.gltf` is the document of the test that runs (routed
// requests are never cached).
let shared = null;
let document_ = '';
async function sharedPage() {
  if (shared) return shared;
  const browser = await chromium.launch({
    executablePath: process.env.LIVEPROBE_CHROMIUM || '/usr/bin/chromium',
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
  const tab = await browser.newPage();
  const errors = [];
  tab.on('pageerror', (e) => errors.push(String(e)));
  await tab.route('http://lp.test/**', (route) => {
    const path = new URL(route.request().url()).pathname;
    const ext = path.slice(path.lastIndexOf('.'));
    const body = path === '/' ? page : path === '/model.gltf' ? document_
      : readFileSync(join(modules, path.replace(/^\/node_modules\//, '')));
    return route.fulfill({ status: 200, contentType: types[ext] || 'text/html', body });
  });
  await tab.goto('http://lp.test/');
  await tab.waitForFunction(() => window.ready === true, null, { timeout: 30000 });
  shared = { browser, tab, errors };
  return shared;
}
after(async () => {
  if (shared) await shared.browser.close();
});

async function withPage(gltf, body) {
  const { tab, errors } = await sharedPage();
  document_ = gltf;
  errors.length = 0;
  const result = await body(tab);
  assert.deepEqual(errors, []);
  return result;
}

// Where the light comes from in a Babylon scene of either handedness: a white diffuse sphere
// (no specular), shaded by Babylon's PBR material from the loaded document (the loader's
// polynomial), against the light the document declares in the glTF frame
// (irradianceCoefficients through Babylon's shader formula, which gltf.test.mjs ties to
// liveprobe's irradiance). Per pixel, the normal Babylon drew is taken to the glTF frame (the
// loader's root turns glTF (x, y, z) into (-x, y, z) of a left-handed scene; a right-handed
// scene is the glTF frame) and the shading is compared with the declared light there and in its
// three mirror images. Babylon shows the mirror image: in x in a left-handed scene, in z in a
// right-handed one (it samples environments as left-handed cube maps and flips z in a
// right-handed scene, the polynomial with them), and it multiplies the light's intensity into the
// polynomial twice; with docs/engines.md's two lines the light is where the document puts it.
for (const rightHanded of [false, true]) {
  const hand = rightHanded ? 'right' : 'left';
  test(`Babylon lights the glTF's scene from the mirror image, and from the document's light with the fix: ${hand}-handed scene`, async () => {
    const gltf = run(['coeffs', join(data, 'equirect/quarry_01_1k.hdr'), '--format', 'gltf']);
    const size = 128;
    const light = JSON.parse(gltf).extensions.EXT_lights_image_based.lights[0];
    assert.ok(light.intensity > 1);  // a sun beyond RGBD's range: the intensity is its scale
    const sh = SphericalHarmonics.FromArray(light.irradianceCoefficients);
    sh.scaleInPlace(light.intensity);
    sh.convertIrradianceToLambertianRadiance();
    sh.preScaleForRendering();
    let brightest = 0;
    for (const d of fibonacciSphere(1000)) brightest = Math.max(brightest, ...harmonicsFunctions(sh, d));
    // The albedo keeps every pixel within 8 bits and above the last few codes: Babylon's second
    // intensity included, as loaded; without it, with the fix.
    const albedoFor = (fixed) => 0.25 / brightest / (fixed ? 1 : light.intensity);
    const lum = (d) => harmonicsFunctions(sh, d).reduce((a, b) => a + b, 0);
    const frames = {
      declared: (g) => g, 'x mirrored': ([x, y, z]) => [-x, y, z],
      'z mirrored': ([x, y, z]) => [x, y, -z], 'x and z mirrored': ([x, y, z]) => [-x, y, -z],
    };
    const fit = async (fixed) => {
      const albedo = albedoFor(fixed);
      const r = await withPage(gltf, (tab) => tab.evaluate(
          ([rh, n, a, f]) => window.shade(rh, n, a, f), [rightHanded, size, albedo, fixed]));
      const shaded = [], seen = Object.fromEntries(Object.keys(frames).map((k) => [k, []]));
      for (let i = 0; i < size * size; ++i) {
        if (r.normal[4 * i + 3] < 255) continue;  // background
        const w = [0, 1, 2].map((c) => r.normal[4 * i + c] / 127.5 - 1);
        const g = rightHanded ? w : [-w[0], w[1], w[2]];
        shaded.push([0, 1, 2].reduce((s, c) => s + (r.shaded[4 * i + c] / 255) ** 2.2, 0));
        for (const [k, f] of Object.entries(frames)) seen[k].push(lum(f(g)));
      }
      assert.ok(shaded.length > size * size / 2, `${shaded.length} sphere pixels`);
      const corr = Object.fromEntries(Object.entries(seen).map(([k, v]) => [k, correlation(shaded, v)]));
      const best = Object.keys(corr).reduce((a, b) => (corr[a] >= corr[b] ? a : b));
      const ratios = shaded.map((v, i) => v / seen[best][i] / albedo).sort((a, b) => a - b);
      const gain = ratios[ratios.length >> 1];
      console.log(`${hand}-handed${fixed ? ', with the fix' : ''}: the shading follows the light ` +
                  Object.entries(corr).map(([k, v]) => `${k} ${v.toFixed(4)}`).join(', ') +
                  `; Babylon's light is ${gain.toFixed(2)} x the declared (intensity ${light.intensity})`);
      return { corr, best, gain };
    };
    const loaded = await fit(false);
    assert.equal(loaded.best, rightHanded ? 'z mirrored' : 'x mirrored');
    assert.ok(loaded.corr[loaded.best] > 0.995, `${loaded.corr[loaded.best]}`);
    assert.ok(Math.abs(loaded.gain / light.intensity - 1) < 0.1, `${loaded.gain}`);
    const fixed = await fit(true);
    assert.equal(fixed.best, 'declared');
    assert.ok(fixed.corr.declared > 0.995, `${fixed.corr.declared}`);
    assert.ok(Math.abs(fixed.gain - 1) < 0.1, `${fixed.gain}`);
  });
}

for (const map of maps) {
  test(`Babylon's loader reads the specular cube as the coefficients' light: ${map.name}`, async () => {
    const gltf = run(['coeffs', join(data, map.file), '--layout', map.layout, '--format', 'gltf']);
    const r = await withPage(gltf, (tab) => tab.evaluate((doc) => window.project(doc), JSON.parse(gltf)));
    // Over 1000 directions, the largest difference relative to the mean of the coefficients'.
    const dirs = fibonacciSphere(1000);
    let mean = 0, worst = 0;
    for (const d of dirs) mean += evalPolynomial(r.coefficients, d).reduce((a, b) => a + b) / 3 / dirs.length;
    for (const d of dirs) {
      const a = evalPolynomial(r.cube, d), b = evalPolynomial(r.coefficients, d);
      for (let c = 0; c < 3; ++c) worst = Math.max(worst, Math.abs(a[c] - b[c]) / mean);
    }
    console.log(`${map.name}: the loaded cube's polynomial against the coefficients': worst ${(100 * worst).toFixed(1)}% of the mean`);
    // What is left is the cube's own error (64 x 64 faces, 8-bit RGBD, half floats): 0.0-0.3%
    // measured; faces upside down: 59-64%.
    assert.ok(worst < 0.02, `${worst}`);
  });
}
