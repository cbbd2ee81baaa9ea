// Babylon's shader formula for SH irradiance, taken from the shader text Babylon ships
// (ShadersInclude/harmonicsFunctions, the SPHERICAL_HARMONICS variant of
// computeEnvironmentIrradiance) and evaluated term by term, so the test runs Babylon's own
// formula, not a copy of it.
import { ShaderStore } from '@babylonjs/core/Engines/shaderStore.js';
import '@babylonjs/core/Shaders/ShadersInclude/harmonicsFunctions.js';

const source = ShaderStore.IncludesShadersStore.harmonicsFunctions;
const body = source.match(/#ifdef SPHERICAL_HARMONICS\s*vec3 computeEnvironmentIrradiance\(vec3 normal\) \{return ([^;]*);\}/);
if (!body) throw new Error('Babylon harmonicsFunctions: the SPHERICAL_HARMONICS formula was not found');

// "vSphericalL00 + vSphericalL1_1*(normal.y) + ..." -> [{ field: 'l00', expr: '1' }, ...]
const terms = body[1].split(/\n\+\s*/).map((t) => {
  const m = t.trim().match(/^vSpherical(L[0-9_]+)(?:\*(.*))?$/);
  if (!m) throw new Error(`Babylon harmonicsFunctions: unexpected term ${t}`);
  return { field: m[1].toLowerCase(), expr: m[2] ?? '1.0' };
});
if (terms.length !== 9) throw new Error(`Babylon harmonicsFunctions: ${terms.length} terms, not 9`);
const fns = terms.map(({ field, expr }) => ({
  field,
  // The expressions use only normal.x/y/z, numbers, + - * and parentheses.
  f: new Function('normal', `return ${expr.replace(/[^0-9a-z_.()+\-* ]/gi, '')};`),
}));

/// computeEnvironmentIrradiance(normal) for pre-scaled SphericalHarmonics `sh`: [r, g, b].
export function harmonicsFunctions(sh, [x, y, z]) {
  const normal = { x, y, z };
  const out = [0, 0, 0];
  for (const { field, f } of fns) {
    const w = f(normal), c = sh[field];
    out[0] += c.x * w, out[1] += c.y * w, out[2] += c.z * w;
  }
  return out;
}
