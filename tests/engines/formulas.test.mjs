// Filament, Unity and WebXR, whose engines do not run here: their published shader formulas,
// written below as they publish them, applied to liveprobe's exports, give liveprobe's
// irradiance. (three.js and Babylon.js are checked with their own code: three.test.mjs,
// babylon.test.mjs.)
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { SphericalHarmonics3, Vector3 } from 'three';
import { coeffs, errorAgainstMap, irradianceMap, maps } from './common.mjs';

/// Filament, shaders/src/light_indirect.fs, Irradiance_SphericalHarmonics (3 bands), with
/// iblSH the 9 pre-scaled coefficients of IndirectLight::Builder::irradiance(3, sh).
function filamentIrradiance(iblSH, n) {
  return [0, 1, 2].map((c) => Math.max(
      iblSH[0][c]
    + iblSH[1][c] * (n.y)
    + iblSH[2][c] * (n.z)
    + iblSH[3][c] * (n.x)
    + iblSH[4][c] * (n.y * n.x)
    + iblSH[5][c] * (n.y * n.z)
    + iblSH[6][c] * (3.0 * n.z * n.z - 1.0)
    + iblSH[7][c] * (n.z * n.x)
    + iblSH[8][c] * (n.x * n.x - n.y * n.y)
    , 0.0));
}

/// Unity: the SphericalHarmonicsL2 packed into unity_SHAr..unity_SHC as the engine packs them
/// for its shaders, then ShadeSH9 (UnityCG.cginc: SHEvalLinearL0L1 + SHEvalLinearL2).
function unityShadeSH9(sh, n) {
  const dot4 = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  const SHA = [0, 1, 2].map((c) => [sh[c][3], sh[c][1], sh[c][2], sh[c][0] - sh[c][6]]);
  const SHB = [0, 1, 2].map((c) => [sh[c][4], sh[c][5], sh[c][6] * 3, sh[c][7]]);
  const SHC = [sh[0][8], sh[1][8], sh[2][8], 1];
  const normal = [n.x, n.y, n.z, 1.0];
  const x = [0, 1, 2].map((c) => dot4(SHA[c], normal));                   // SHEvalLinearL0L1
  const vB = [n.x * n.y, n.y * n.z, n.z * n.z, n.z * n.x];                 // normal.xyzz * normal.yzzx
  const x1 = [0, 1, 2].map((c) => dot4(SHB[c], vB));
  const vC = n.x * n.x - n.y * n.y;
  return [0, 1, 2].map((c) => x[c] + x1[c] + SHC[c] * vC);                // SHEvalLinearL2
}

/// The engine's E (a function of its own frame's normal) against liveprobe's map.
function compare(map, frame, engineE, clampNegative) {
  return errorAgainstMap(irradianceMap(map), (d) => engineE(frame(d)), clampNegative);
}

const vec = ([x, y, z]) => ({ x, y, z });

for (const map of maps) {
  test(`Filament's Irradiance_SphericalHarmonics: ${map.name}`, () => {
    const c = coeffs(map, 'filament');
    // Filament (x, y, z) = (y, z, -x) of liveprobe's frame (cmgen's equirect lookup, mirrored).
    const err = compare(map, ([x, y, z]) => vec([y, z, -x]),
                        (n) => filamentIrradiance(c.irradiance, n).map((v) => v * Math.PI), true);
    console.log(`filament ${map.name}: ${err.toExponential(2)}`);
    assert.ok(err < 1e-4, `${err}`);
  });

  test(`Unity's ShadeSH9: ${map.name}`, () => {
    const c = coeffs(map, 'unity');
    // Unity (x, y, z) = (-x, z, y) of liveprobe's frame (Skybox/Panoramic's ToRadialCoords).
    const err = compare(map, ([x, y, z]) => vec([-x, z, y]),
                        (n) => unityShadeSH9(c.sh, n).map((v) => v * Math.PI), false);
    console.log(`unity ${map.name}: ${err.toExponential(2)}`);
    assert.ok(err < 1e-4, `${err}`);
  });

  test(`WebXR sphericalHarmonicsCoefficients as three's XREstimatedLight uses them: ${map.name}`, () => {
    const c = coeffs(map, 'webxr');
    assert.equal(c.sphericalHarmonicsCoefficients.length, 27);
    const sh = new SphericalHarmonics3().fromArray(c.sphericalHarmonicsCoefficients);
    const out = new Vector3();
    // The XR reference space as three uses it: three's frame, (-x, z, -y) of liveprobe's.
    const err = compare(map, ([x, y, z]) => new Vector3(-x, z, -y),
                        (n) => sh.getIrradianceAt(n, out).toArray(), false);
    console.log(`webxr ${map.name}: ${err.toExponential(2)}`);
    assert.ok(err < 1e-4, `${err}`);
  });
}

test('the primary light of a webxr export is the sun of the three export', () => {
  const map = { file: 'equirect/pedestrian_overpass_1k.hdr', layout: 'equirect' };
  const x = coeffs(map, 'webxr', ['--sun']), t = coeffs(map, 'three', ['--sun']);
  const d = x.primaryLightDirection, s = t.directionalLights[0];
  assert.deepEqual([d.x, d.y, d.z], s.direction);
  const p = x.primaryLightIntensity;
  for (const [a, b] of [[p.x, s.color[0]], [p.y, s.color[1]], [p.z, s.color[2]]])
    assert.ok(Math.abs(a - b * s.intensity) <= 1e-5 * s.intensity);
});
