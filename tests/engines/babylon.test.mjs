// Babylon.js's own code against liveprobe's `babylon` export.
// 1. The frame: Babylon's own HDR pipeline (HDRTools.GetCubeMapTextureData, i.e.
//    PanoramaToCubeMapTools, then CubeMapToSphericalPolynomialTools, as HDRCubeTexture does)
//    turns the same panorama into a SphericalPolynomial. liveprobe's exported polynomial matches
//    it, and of the 48 signed permutations of the axes it is the identity that matches best.
// 2. The evaluation: SphericalPolynomial.FromHarmonics of the exported harmonics is the exported
//    polynomial, and the pre-scaled harmonics (preScaleForRendering) in Babylon's shader formula
//    (computeEnvironmentIrradiance, harmonicsFunctions) give liveprobe's irradiance / pi.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { HDRTools } from '@babylonjs/core/Misc/HighDynamicRange/hdr.js';
import { CubeMapToSphericalPolynomialTools } from '@babylonjs/core/Misc/HighDynamicRange/cubemapToSphericalPolynomial.js';
import { SphericalHarmonics, SphericalPolynomial } from '@babylonjs/core/Maths/sphericalPolynomial.js';
import { harmonicsFunctions } from './babylon_shader.mjs';
import { coeffs, data, errorAgainstMap, irradianceMap, maps, relativeError, signedPermutations } from './common.mjs';

const kPolyKeys = ['x', 'y', 'z', 'xx', 'yy', 'zz', 'yz', 'zx', 'xy'];
const kShKeys = ['l00', 'l1_1', 'l10', 'l11', 'l2_2', 'l2_1', 'l20', 'l21', 'l22'];

function evalPolynomial(p, [x, y, z]) {
  const m = { x, y, z, xx: x * x, yy: y * y, zz: z * z, yz: y * z, zx: z * x, xy: x * y };
  return [0, 1, 2].map((ch) => kPolyKeys.reduce((s, k) => s + p[k][ch] * m[k], 0));
}

/// 1000 directions spread evenly over the sphere (a Fibonacci lattice).
const sphere = Array.from({ length: 1000 }, (_, i) => {
  const z = 1 - (2 * i + 1) / 1000, r = Math.sqrt(1 - z * z), p = i * Math.PI * (3 - Math.sqrt(5));
  return [r * Math.cos(p), r * Math.sin(p), z];
});

for (const map of maps.filter((m) => m.layout === 'equirect')) {
  test(`Babylon's own panorama pipeline agrees with the export's frame: ${map.name}`, () => {
    const buf = readFileSync(join(data, map.file));
    const bytes = new Uint8Array(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength));
    // Babylon samples the panorama by nearest pixel: faces as wide as the panorama (at most 512)
    // keep small bright sources' power.
    const width = HDRTools.RGBE_ReadHeader(bytes).width;
    const poly = CubeMapToSphericalPolynomialTools.ConvertCubeMapToSphericalPolynomial(
        HDRTools.GetCubeMapTextureData(bytes, Math.min(width, 512), false));
    const theirs = Object.fromEntries(kPolyKeys.map((k) => [k, [poly[k].x, poly[k].y, poly[k].z]]));
    const ours = coeffs(map, 'babylon').polynomial;
    const errors = signedPermutations().map((Q) =>
        relativeError(sphere.map((n) => [evalPolynomial(ours, Q(n)), evalPolynomial(theirs, n)])));
    const best = Math.min(...errors.slice(1));
    console.log(`${map.name}: ${(100 * errors[0]).toFixed(2)}% in liveprobe's frame; ` +
                `the best other axis choice ${(100 * best).toFixed(1)}%`);
    assert.ok(errors[0] < 0.02, `${errors[0]}`);
    assert.ok(best > 4 * errors[0], `another frame fits nearly as well: ${best}`);
  });
}

for (const map of maps) {
  test(`Babylon's SH evaluation equals liveprobe's irradiance: ${map.name}`, () => {
    const c = coeffs(map, 'babylon');
    const sh = SphericalHarmonics.FromArray(kShKeys.map((k) => c.harmonics[k]));
    const poly = SphericalPolynomial.FromHarmonics(sh);
    for (const k of kPolyKeys)
      for (let ch = 0; ch < 3; ++ch)
        assert.ok(Math.abs(poly[k].asArray()[ch] - c.polynomial[k][ch]) <=
                      1e-5 * Math.abs(poly.xx.asArray()[ch]), `polynomial ${k}`);
    sh.preScaleForRendering();
    // Babylon's frame: (x, y, z) = (-y, z, -x) of liveprobe's (checked by the test above).
    const err = errorAgainstMap(irradianceMap(map), ([x, y, z]) =>
        harmonicsFunctions(sh, [-y, z, -x]).map((v) => v * Math.PI));
    console.log(`${map.name}: max |Babylon - liveprobe| / max E = ${err.toExponential(2)}`);
    assert.ok(err < 1e-4, `relative error ${err}`);
  });
}
