// The glTF export's specular cube through Babylon.js's own glTF loader (npm @babylonjs/loaders,
// its EXT_lights_image_based extension) in Debian's chromium, headless (WebGL on SwiftShader):
// the cube Babylon builds from the face images, projected by Babylon's own
// CubeMapToSphericalPolynomialTools, is the light of the exported irradianceCoefficients (the
// polynomial the same loader makes of them). A cube stored upside down fails it.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { data, maps, run } from './common.mjs';

const modules = join(dirname(fileURLToPath(import.meta.url)), 'node_modules');
const page = `<!doctype html><canvas id="c" width="64" height="64"></canvas>
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
import '@babylonjs/loaders/glTF/2.0/index.js';
window.project = async (gltf) => {
  const engine = new Engine(document.getElementById('c'));
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
  return { cube: asObject(cube), coefficients: asObject(fromCoefficients), info };
};
window.ready = true;
</script>`;

function evalPolynomial(p, [x, y, z]) {
  const m = { x, y, z, xx: x * x, yy: y * y, zz: z * z, yz: y * z, zx: z * x, xy: x * y };
  return [0, 1, 2].map((ch) => Object.keys(m).reduce((s, k) => s + p[k][ch] * m[k], 0));
}

const types = { '.js': 'text/javascript', '.html': 'text/html', '.gltf': 'model/gltf+json' };

for (const map of maps) {
  test(`Babylon's loader reads the specular cube as the coefficients' light: ${map.name}`, async () => {
    const gltf = run(['coeffs', join(data, map.file), '--layout', map.layout, '--format', 'gltf']);
    const browser = await chromium.launch({
      executablePath: process.env.LIVEPROBE_CHROMIUM || '/usr/bin/chromium',
      args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
    });
    try {
      const tab = await browser.newPage();
      const errors = [];
      tab.on('pageerror', (e) => errors.push(String(e)));
      await tab.route('http://lp.test/**', (route) => {
        const path = new URL(route.request().url()).pathname;
        const ext = path.slice(path.lastIndexOf('.'));
        const body = path === '/' ? page : path === '/model.gltf' ? gltf
          : readFileSync(join(modules, path.replace(/^\/node_modules\//, '')));
        return route.fulfill({ status: 200, contentType: types[ext] || 'text/html', body });
      });
      await tab.goto('http://lp.test/');
      await tab.waitForFunction(() => window.ready === true, null, { timeout: 30000 });
      const r = await tab.evaluate((doc) => window.project(doc), JSON.parse(gltf));
      assert.deepEqual(errors, []);
      // Over 1000 directions, the largest difference relative to the mean of the coefficients'.
      const dirs = Array.from({ length: 1000 }, (_, i) => {
        const z = 1 - (2 * i + 1) / 1000, s = Math.sqrt(1 - z * z), p = i * Math.PI * (3 - Math.sqrt(5));
        return [s * Math.cos(p), s * Math.sin(p), z];
      });
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
    } finally {
      await browser.close();
    }
  });
}
