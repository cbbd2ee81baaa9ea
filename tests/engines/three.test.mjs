// three.js's own code evaluates liveprobe's `three` export: SphericalHarmonics3.getIrradianceAt
// of the LightProbe that three's ObjectLoader builds from it, at the directions three's own
// equirect lookup (equirectUv) gives the texels of liveprobe's irradiance map as three loads it
// (EXRLoader), equals liveprobe's irradiance there.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { ObjectLoader, Vector3, FloatType } from 'three';
import { HDRLoader } from 'three/examples/jsm/loaders/HDRLoader.js';
import { coeffs, data, irradianceMap, maps, relativeError } from './common.mjs';

/// The LightProbe three's ObjectLoader makes of an exported object (LightProbe.toJSON's form).
function lightProbe(c) {
  const json = {
    metadata: { version: 4.6, type: 'Object', generator: 'Object3D.toJSON' },
    object: { uuid: '00000000-0000-4000-8000-000000000000', type: 'LightProbe', layers: 1,
              matrix: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1], up: [0, 1, 0],
              sh: c.sh, intensity: c.intensity },
  };
  return new ObjectLoader().parse(json);
}

/// three's equirectUv (ShaderChunk common.glsl.js), as three writes it.
function equirectUv(d) {
  const u = Math.atan2(d[2], d[0]) * (0.5 / Math.PI) + 0.5;
  const v = Math.asin(Math.min(Math.max(d[1], -1), 1)) * (1 / Math.PI) + 0.5;
  return [u, v];
}

/// Its inverse: the direction three shows texel coordinate (u, v) of an equirect texture in.
function equirectDir(u, v) {
  const lat = (v - 0.5) * Math.PI, lon = (u - 0.5) * 2 * Math.PI;
  return [Math.cos(lat) * Math.cos(lon), Math.sin(lat), Math.cos(lat) * Math.sin(lon)];
}

for (const map of maps) {
  test(`three.js getIrradianceAt equals liveprobe's irradiance: ${map.name}`, () => {
    const probe = lightProbe(coeffs(map, 'three'));
    const e = irradianceMap(map);
    const pairs = [];
    const out = new Vector3();
    for (let r = 0; r < e.height; ++r)
      for (let c = 0; c < e.width; ++c) {
        // The EXR's data as three holds it (rows bottom-up, flipY false): texel (c, r) is at
        // uv ((c + 0.5) / W, (r + 0.5) / H).
        const d = equirectDir((c + 0.5) / e.width, (r + 0.5) / e.height);
        const [u, v] = equirectUv(d);  // the lookup really lands on that texel
        assert.ok(Math.abs(u * e.width - c - 0.5) < 1e-6 && Math.abs(v * e.height - r - 0.5) < 1e-6);
        probe.sh.getIrradianceAt(new Vector3(...d), out);
        pairs.push([[out.x * probe.intensity, out.y * probe.intensity, out.z * probe.intensity],
                    e.rawRow(c, r)]);
      }
    const err = relativeError(pairs);
    console.log(`${map.name}: max |three - liveprobe| / max E = ${err.toExponential(2)}`);
    assert.ok(err < 1e-4, `relative error ${err}`);
  });
}

test('the sun of a three export lies where three shows the brightest pixel', () => {
  const map = { file: 'equirect/pedestrian_overpass_1k.hdr', layout: 'equirect' };
  const c = coeffs(map, 'three', ['--sun']);
  assert.equal(c.directionalLights.length, 1);
  const buf = readFileSync(join(data, map.file));
  const loader = new HDRLoader();
  loader.setDataType(FloatType);
  const t = loader.parse(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength));
  // HDRLoader's texture has flipY true: data row 0 is the file's top row, shown at v = 1.
  let best = -1, bi = 0;
  for (let i = 0; i < t.width * t.height; ++i) {
    const y = 0.2126 * t.data[i * 4] + 0.7152 * t.data[i * 4 + 1] + 0.0722 * t.data[i * 4 + 2];
    if (y > best) best = y, bi = i;
  }
  const col = bi % t.width, row = Math.floor(bi / t.width);
  const sun = equirectDir((col + 0.5) / t.width, 1 - (row + 0.5) / t.height);
  const d = c.directionalLights[0].direction;
  const deg = Math.acos(Math.min(1, sun[0] * d[0] + sun[1] * d[1] + sun[2] * d[2])) * 180 / Math.PI;
  console.log(`sun: ${deg.toFixed(3)} degrees from three's brightest texel`);
  assert.ok(deg < 1.0, `${deg} degrees`);
});
