// The page of replay --serve in a real browser: Debian's chromium, headless (WebGL on
// SwiftShader), driven by playwright-core. It loads three.js from liveprobe's own server (no
// network), receives frames, and the colour at the centre of the lit white sphere (normal
// towards the camera, three's +z) is albedo * E / pi of the frame it shows, E from three.js's
// own getIrradianceAt of that frame's LightProbe plus its DirectionalLight. The screenshot is
// README's picture of the page.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { chromium } from 'playwright-core';
import { SphericalHarmonics3, Vector3 } from 'three';
import { data } from './common.mjs';
import { serve } from './serve.mjs';

const srgb = (v) => (v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055);

test('the page draws the model lit by the stream', async () => {
  const s = serve([join(data, 'equirect/pedestrian_overpass_1k.hdr'), '--loop', '--headless', '--size', '64x36',
                   '--duration', '60', '--serve', '0', '--sun', '--quiet']);
  const port = await s.port;
  const browser = await chromium.launch({
    executablePath: process.env.LIVEPROBE_CHROMIUM || '/usr/bin/chromium',
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
  try {
    const page = await browser.newPage({ viewport: { width: 640, height: 360 } });
    const failed = [];
    page.on('requestfailed', (r) => failed.push(r.url()));
    page.on('response', (r) => { if (r.status() >= 400) failed.push(`${r.status()} ${r.url()}`); });
    await page.goto(`http://127.0.0.1:${port}/?freeze=1`);
    await page.waitForFunction(() => {
      const t = document.getElementById('state').textContent;
      return t && JSON.parse(t).frames >= 10;  // it keeps receiving
    }, null, { timeout: 30000 });
    await page.waitForTimeout(500);  // a few more animation frames of the frozen frame
    const state = JSON.parse(await page.textContent('#state'));
    const pixel = await page.evaluate(() => {
      const c = document.querySelector('canvas');
      const g = document.createElement('canvas');
      g.width = c.width, g.height = c.height;
      const ctx = g.getContext('2d');
      ctx.drawImage(c, 0, 0);
      return Array.from(ctx.getImageData(c.width / 2, c.height / 2, 1, 1).data);
    });
    const out = process.env.LIVEPROBE_TEST_OUTPUT;
    if (out) {
      mkdirSync(out, { recursive: true });
      await page.screenshot({ path: join(out, 'web_page.png') });
    }
    assert.deepEqual(failed, [], 'every request the page made was answered');
    // E at the sphere's centre, normal (0, 0, 1) in three's frame, from three's own code.
    const c = state.coefficients;
    const n = new Vector3(0, 0, 1);
    const e = new SphericalHarmonics3().fromArray(c.sh).getIrradianceAt(n, new Vector3());
    for (const l of c.directionalLights) {
      const cos = Math.max(0, n.dot(new Vector3(...l.direction)));
      e.add(new Vector3(...l.color).multiplyScalar(cos * l.intensity));
    }
    const expected = e.toArray().map((v) => 255 * srgb(Math.min(1, (v * state.exposure) / Math.PI)));
    console.log(`frame ${state.frame}: centre pixel ${pixel.slice(0, 3).join(', ')}, ` +
                `expected ${expected.map((v) => v.toFixed(1)).join(', ')}`);
    // Tolerance: 3 codes of 255 (8-bit output and the sphere's tessellation at the centre).
    for (let ch = 0; ch < 3; ++ch) assert.ok(Math.abs(pixel[ch] - expected[ch]) <= 3, `channel ${ch}`);
  } finally {
    await browser.close();
    s.proc.kill('SIGINT');
    await s.exited;
  }
});
