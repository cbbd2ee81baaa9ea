// Shared by the engine tests: running liveprobe, reading its irradiance maps with three.js's own
// EXR loader, and the directions of liveprobe's equirect convention (liveprobe/sh/sh.h).
import { execFileSync } from 'node:child_process';
import { readFileSync, mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { EXRLoader } from 'three/examples/jsm/loaders/EXRLoader.js';
import { FloatType } from 'three';

export const liveprobe = process.env.LIVEPROBE_BIN || 'liveprobe';
export const data = process.env.LIVEPROBE_DATA || fileURLToPath(new URL('../../../shared/data', import.meta.url));

/// The maps of the issue: Grace (lat-long), Venice (equirect), the beach (angular).
export const maps = [
  { name: 'grace', file: 'probes/latlong_256x128/grace.hdr', layout: 'equirect' },
  { name: 'venice', file: 'equirect/venice_sunset_1k.hdr', layout: 'equirect' },
  { name: 'beach', file: 'probes/beach_probe.hdr', layout: 'angular' },
];

export function run(args) {
  return execFileSync(liveprobe, args, { encoding: 'utf8', maxBuffer: 1 << 28 });
}

export function coeffs(map, format, extra = []) {
  const out = run(['coeffs', join(data, map.file), '--layout', map.layout, '--format', format, ...extra]);
  return JSON.parse(out).coefficients;
}

/// liveprobe's irradiance map of `map` (sh method), W x H equirect indexed by normal, read by
/// three's EXRLoader: { width, height, at(col, fileRow) -> [r, g, b] } with fileRow 0 the top.
export function irradianceMap(map, width = 64, height = 32) {
  const dir = mkdtempSync(join(tmpdir(), 'lp-engines-'));
  const path = join(dir, 'e.exr');
  run(['irradiance', join(data, map.file), '--layout', map.layout, '--size', `${width}x${height}`, '--out', path]);
  const buf = readFileSync(path);
  const loader = new EXRLoader();
  loader.setDataType(FloatType);
  const t = loader.parse(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength));
  const stride = t.data.length / (t.width * t.height);
  // EXRLoader stores rows bottom-up (a texture with flipY false): data row r is file row H-1-r.
  const at = (c, fileRow) => {
    const i = ((t.height - 1 - fileRow) * t.width + c) * stride;
    return [t.data[i], t.data[i + 1], t.data[i + 2]];
  };
  return { width: t.width, height: t.height, at, rawRow: (c, r) => at(c, t.height - 1 - r) };
}

/// liveprobe's direction of pixel (col, fileRow) of a W x H equirect (liveprobe/sh/sh.h).
export function liveprobeDir(c, i, w, h) {
  const t = Math.PI * (i + 0.5) / h, p = 2 * Math.PI * (c + 0.5) / w;
  return [Math.sin(t) * Math.cos(p), Math.sin(t) * Math.sin(p), Math.cos(t)];
}

/// Largest |a - b| over all channels and samples, relative to the largest |b|.
export function relativeError(pairs) {
  let err = 0, scale = 0;
  for (const [a, b] of pairs)
    for (let ch = 0; ch < 3; ++ch) {
      err = Math.max(err, Math.abs(a[ch] - b[ch]));
      scale = Math.max(scale, Math.abs(b[ch]));
    }
  return err / scale;
}

/// How far an engine's irradiance is from liveprobe's map `e`: engineE(d) is the engine's E at
/// liveprobe's direction d (the test turns d into the engine's frame); relativeError of the two.
/// clampNegative: compare with max(E, 0) (an engine that clamps).
export function errorAgainstMap(e, engineE, clampNegative = false) {
  const pairs = [];
  for (let i = 0; i < e.height; ++i)
    for (let j = 0; j < e.width; ++j) {
      const ours = e.at(j, i).map((v) => (clampNegative ? Math.max(v, 0) : v));
      pairs.push([engineE(liveprobeDir(j, i, e.width, e.height)), ours]);
    }
  return relativeError(pairs);
}

/// The 48 signed permutations of the axes: every frame a convention slip could produce.
export function signedPermutations() {
  const out = [];
  const perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
  for (const p of perms)
    for (let s = 0; s < 8; ++s)
      out.push((v) => p.map((axis, i) => ((s >> i) & 1 ? -1 : 1) * v[axis]));
  return out;
}
