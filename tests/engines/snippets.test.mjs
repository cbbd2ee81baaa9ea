// The engine snippets of docs/engines.md, as written. Each names the command whose output it
// reads in its first line ("// three.js: liveprobe coeffs MAP --sun --format three > three.json");
// that command runs on a sunlit map, then:
// - the three.js, Babylon.js and WebXR snippets run under node with the engines' own code (their
//   `import` lines bound to the real modules, `fetch` reading the file), and what they built is
//   checked against the file: three's LightProbe and DirectionalLights, the polynomial Babylon's
//   environment texture holds, the WebXR probe's coefficients;
// - the Filament (C++) and Unity (C#) snippets, whose engines do not run here, have the JSON path
//   they read looked up in the real output, with the shape their loops index;
// - the glTF description names extensions and fields the real file holds.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, writeFileSync, mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import * as THREE from 'three';
import * as BABYLON from '@babylonjs/core';
import { data, run } from './common.mjs';

const docs = fileURLToPath(new URL('../../docs/engines.md', import.meta.url));
const map = join(data, 'equirect/pedestrian_overpass_1k.hdr');  // a clear sun
const dir = mkdtempSync(join(tmpdir(), 'lp-snippets-'));
const modules = { three: THREE, '@babylonjs/core': BABYLON };

/// Every fenced block of the page with its language, name and command.
const blocks = [...readFileSync(docs, 'utf8').matchAll(/```(js|cpp|csharp|text)\n([\s\S]*?)```/g)]
  .map(([, lang, body]) => {
    const m = body.match(/^(?:\/\/ )?([\w.-]+(?: [\w.-]+)?): liveprobe (coeffs MAP [^>]*)> (\S+)/);
    return m && { lang, body, name: m[1], args: m[2].trim().split(/\s+/), file: m[3] };
  })
  .filter(Boolean);

/// Runs the snippet's command with MAP a real map; the parsed output.
function output(block) {
  const args = block.args.map((a) => (a === 'MAP' ? map : a));
  const text = run(args);
  writeFileSync(join(dir, block.file), text);
  return JSON.parse(text);
}

/// Runs a JS snippet: its imports bound to the real modules, `fetch` reading files of `dir`.
async function runJs(block, globals) {
  const body = block.body.replace(
    /^import (\* as (\w+)|\{([^}]*)\}) from '([^']+)';$/gm,
    (_, _what, star, names, mod) =>
      star ? `const ${star} = __modules['${mod}'];` : `const {${names}} = __modules['${mod}'];`);
  const fetch = async (name) => ({ json: async () => JSON.parse(readFileSync(join(dir, name), 'utf8')) });
  const AsyncFunction = (async () => {}).constructor;
  const names = Object.keys(globals);
  await new AsyncFunction('__modules', 'fetch', ...names, body)(modules, fetch, ...names.map((n) => globals[n]));
}

const byName = (prefix) => {
  const b = blocks.find((x) => x.name.startsWith(prefix));
  assert.ok(b, `docs/engines.md has a ${prefix} snippet`);
  return b;
};

const close = (a, b, what) =>
  a.forEach((v, i) => assert.ok(Math.abs(v - b[i]) <= 1e-6 * (1 + Math.abs(b[i])), `${what}[${i}]: ${v} vs ${b[i]}`));

test('the three.js snippet builds the probe and the sun from the file', async () => {
  const block = byName('three.js');
  const c = output(block).coefficients;
  const scene = new THREE.Scene();
  await runJs(block, { scene });
  const probes = scene.children.filter((o) => o.isLightProbe);
  assert.equal(probes.length, 1);
  close(probes[0].sh.toArray(), c.sh, 'sh');
  assert.equal(probes[0].intensity, c.intensity);
  const suns = scene.children.filter((o) => o.isDirectionalLight);
  assert.ok(c.directionalLights.length >= 1, 'the map has a sun');
  assert.equal(suns.length, c.directionalLights.length);
  close(suns[0].position.clone().normalize().toArray(), c.directionalLights[0].direction, 'direction');
  assert.equal(suns[0].intensity, c.directionalLights[0].intensity);
});

test("the Babylon.js snippet gives the environment the file's polynomial", async () => {
  const block = byName('Babylon.js');
  const c = output(block).coefficients;
  const engine = new BABYLON.NullEngine();
  const scene = new BABYLON.Scene(engine);
  scene.environmentTexture = new BABYLON.BaseTexture(
    scene, new BABYLON.InternalTexture(engine, BABYLON.InternalTextureSource.Unknown));
  await runJs(block, { scene });
  const p = scene.environmentTexture.sphericalPolynomial;
  assert.ok(p, 'the environment texture holds a polynomial');
  for (const k of ['x', 'y', 'z', 'xx', 'yy', 'zz', 'yz', 'zx', 'xy'])
    close(p[k].asArray(), c.polynomial[k], `polynomial.${k}`);
  engine.dispose();
});

test("the WebXR snippet fills the probe with the file's coefficients", async () => {
  const block = byName('WebXR');
  const c = output(block).coefficients;
  const lightProbe = new THREE.LightProbe();
  await runJs(block, { lightProbe });
  close(lightProbe.sh.toArray(), c.sphericalHarmonicsCoefficients, 'sh');
});

/// The value at a JSON path, the path as a snippet writes it: ["a"]["b"] or .a.b
function at(json, path) {
  const keys = [...path.matchAll(/\["(\w+)"\]|\.(\w+)/g)].map((m) => m[1] || m[2]);
  return keys.reduce((v, k) => (v === undefined ? v : v[k]), json);
}
const shape = (v) => (Array.isArray(v) ? [v.length, ...shape(v[0])] : []);

test('the Filament snippet reads a 9 x 3 array where it looks', () => {
  const block = byName('Filament');
  const path = block.body.match(/j((?:\["\w+"\])+);/)[1];  // const auto& e = j["..."]["..."];
  const e = at(output(block), path);
  assert.deepEqual(shape(e), [9, 3], `j${path}`);
  assert.ok(e.flat().every(Number.isFinite));
});

test('the Unity snippet reads a 3 x 9 array where it looks', () => {
  const block = byName('Unity');
  const path = block.body.match(/json((?:\.\w+)+)\[c\]\[i\]/)[1];  // json.coefficients.sh[c][i]
  const sh = at(output(block), path);
  assert.deepEqual(shape(sh), [3, 9], `json${path}`);
  assert.ok(sh.flat().every(Number.isFinite));
});

test('the glTF description names what the file holds', () => {
  const block = byName('glTF');
  const g = output(block);
  for (const ext of ['EXT_lights_image_based', 'KHR_lights_punctual']) {
    assert.ok(block.body.includes(ext));
    assert.ok(g.extensionsUsed.includes(ext), `${ext} used`);
  }
  const ibl = g.extensions.EXT_lights_image_based.lights[0];
  assert.ok(block.body.includes('irradianceCoefficients'));
  assert.deepEqual(shape(ibl.irradianceCoefficients), [9, 3]);
  assert.equal(ibl.specularImageSize, 64);  // "mips 64/32/16"
  assert.equal(ibl.specularImages.length, 3);
  const lights = g.extensions.KHR_lights_punctual.lights;
  assert.ok(lights.length >= 1 && lights.length <= 2, '--lights 2: one or two lights');
});
