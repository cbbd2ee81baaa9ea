// The glTF export: the Khronos validator (npm gltf-validator) reports no errors, and the
// irradianceCoefficients, read as Babylon's EXT_lights_image_based loader reads them
// (SphericalHarmonics.FromArray, convertIrradianceToLambertianRadiance), give liveprobe's
// irradiance in the glTF frame through Babylon's shader formula.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import validator from 'gltf-validator';
import { SphericalHarmonics } from '@babylonjs/core/Maths/sphericalPolynomial.js';
import { harmonicsFunctions } from './babylon_shader.mjs';
import { data, errorAgainstMap, irradianceMap, maps, run } from './common.mjs';
import { join } from 'node:path';

for (const [map, extra] of [[maps[0], ['--lights', '2']], [maps[2], []]]) {
  test(`the Khronos validator finds no error in a glTF export: ${map.name}`, async () => {
    const text = run(['coeffs', join(data, map.file), '--layout', map.layout, '--format', 'gltf', ...extra]);
    const report = await validator.validateBytes(new TextEncoder().encode(text));
    const messages = report.issues.messages.map((m) => `${m.severity} ${m.code} ${m.pointer ?? ''}: ${m.message}`);
    console.log(`${map.name}: ${report.issues.numErrors} errors, ${report.issues.numWarnings} warnings, ` +
                `${report.issues.numInfos} infos\n  ${messages.join('\n  ')}`);
    assert.equal(report.issues.numErrors, 0);
    const gltf = JSON.parse(text);
    const light = gltf.extensions.EXT_lights_image_based.lights[0];
    assert.equal(light.specularImages.length, 3);
    assert.ok(light.specularImages.every((mip) => mip.length === 6));
    if (extra.length) assert.equal(gltf.extensions.KHR_lights_punctual.lights.length, 2);

    const sh = SphericalHarmonics.FromArray(light.irradianceCoefficients);
    sh.scaleInPlace(light.intensity);  // as the loader does: the scale of a map beyond RGBD's range
    sh.convertIrradianceToLambertianRadiance();
    sh.preScaleForRendering();
    if (!extra.length) {  // (with lights split off, the coefficients are the sky alone)
      // glTF (x, y, z) = (-y, z, x) of liveprobe's frame (liveprobe's own GL frame).
      const err = errorAgainstMap(irradianceMap(map), ([x, y, z]) =>
          harmonicsFunctions(sh, [-y, z, x]).map((v) => v * Math.PI));
      assert.ok(err < 1e-4, `${err}`);
    }
  });
}
