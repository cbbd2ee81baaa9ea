// The page of replay --serve in a real browser: Debian's chromium, headless (WebGL on
// SwiftShader), driven by playwright-core. It loads three.js from liveprobe's own server (no
// network), receives frames, and the colour at the centre of the lit white sphere (normal
// towards the camera, three's +z) is albedo * E / pi of the frame it shows, E from three.js's
// own getIrradianceAt of that frame's LightProbe plus its DirectionalLight; and the sun's shadow
// on the ground is darker than the ground it lights. The screenshot is docs/engines.md's picture
// of the page.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { copyFileSync, mkdirSync, mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { chromium } from 'playwright-core';
import { SphericalHarmonics3, Vector3 } from 'three';
import { fileURLToPath } from 'node:url';
import { serve } from './serve.mjs';

const chromiumOptions = {
  executablePath: process.env.LIVEPROBE_CHROMIUM || '/usr/bin/chromium',
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
};

const srgb = (v) => (v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055);

test('the page draws the model lit by the stream', async () => {
  // The bundled HDR sky: a sun 30 degrees up, whose shadow falls on the ground beside the sphere.
  const sky = fileURLToPath(new URL('../../recordings/sky-hdr', import.meta.url));
  const s = serve([sky, '--loop', '--headless', '--size', '64x36', '--duration', '60', '--serve', '0',
                   '--sun', '--quiet']);
  const port = await s.port;
  const browser = await chromium.launch(chromiumOptions);
  try {
    const page = await browser.newPage({ viewport: { width: 640, height: 360 } });
    const failed = [];
    page.on('requestfailed', (r) => failed.push(r.url()));
    page.on('response', (r) => { if (r.status() >= 400) failed.push(`${r.status()} ${r.url()}`); });
    const warned = [];  // three.js warns of what it no longer has (a removed shadow type, say)
    page.on('console', (m) => { if (m.type() === 'warning' || m.type() === 'error') warned.push(m.text()); });
    await page.goto(`http://127.0.0.1:${port}/?freeze=1`);
    await page.waitForFunction(() => {
      const t = document.getElementById('state').textContent;
      return t && JSON.parse(t).frames >= 10;  // it keeps receiving
    }, null, { timeout: 30000 });
    await page.waitForTimeout(500);  // a few more animation frames of the frozen frame
    const state = JSON.parse(await page.textContent('#state'));
    const at = (x, y) => page.evaluate(([x, y]) => {
      const c = document.querySelector('body > canvas');  // three's, not the panel's plot
      const g = document.createElement('canvas');
      g.width = c.width, g.height = c.height;
      const ctx = g.getContext('2d');
      ctx.drawImage(c, 0, 0);
      return Array.from(ctx.getImageData(x, y, 1, 1).data);
    }, [x, y]);
    const pixel = await at(320, 180);
    assert.deepEqual(failed, [], 'every request the page made was answered');
    assert.deepEqual(warned.filter((t) => /THREE/.test(t)), [], 'three.js warned of nothing');
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
    // The sun's shadow: the ground where the sphere hides the sun against the ground beside it.
    assert.ok(state.shadow, 'the sun is high enough to cast a shadow on the ground');
    const dark = await at(...state.shadow.inShadow), lit = await at(...state.shadow.lit);
    const luma = (p) => 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    console.log(`ground in shadow ${dark.slice(0, 3).join(', ')}, lit ${lit.slice(0, 3).join(', ')}`);
    assert.ok(luma(dark) < 0.7 * luma(lit), 'the shadow is darker than the lit ground');
    // The picture of the page: live (not frozen), after a few seconds of the stream's plot.
    const out = process.env.LIVEPROBE_TEST_OUTPUT;
    if (out) {
      mkdirSync(out, { recursive: true });
      await page.goto(`http://127.0.0.1:${port}/`);
      await page.waitForTimeout(4000);
      // The DevTools protocol's capture of the compositor's frame: Playwright's page.screenshot
      // does not return on a page that redraws its WebGL canvas every animation frame on
      // SwiftShader (Chromium 156), while this takes the frame on screen.
      const cdp = await page.context().newCDPSession(page);
      const shot = await cdp.send('Page.captureScreenshot', { format: 'png' });
      writeFileSync(join(out, 'web_page.png'), Buffer.from(shot.data, 'base64'));
    }
  } finally {
    await browser.close();
    s.proc.kill('SIGINT');
    await s.exited;
  }
});

// A page served without three.js (LIVEPROBE_WEB_DIR naming a folder without it) says so in the browser,
// in its status line, with what to do; the terminal's warning is not the only word.
test('without three.js the page says what is missing', async () => {
  const web = mkdtempSync(join(tmpdir(), 'lp-web-'));
  for (const f of ['index.html', 'main.js'])
    copyFileSync(fileURLToPath(new URL(`../../app/web/${f}`, import.meta.url)), join(web, f));
  const s = serve(['synthetic:64x32', '--headless', '--size', '32x18', '--duration', '60', '--serve', '0',
                   '--quiet'], { LIVEPROBE_WEB_DIR: web });
  const port = await s.port;
  const browser = await chromium.launch(chromiumOptions);
  try {
    const page = await browser.newPage();
    await page.goto(`http://127.0.0.1:${port}/`);
    await page.waitForFunction(() => document.getElementById('status').className === 'bad', null,
                               { timeout: 30000 });
    const status = await page.textContent('#status');
    assert.match(status, /three\.js did not load/);
    assert.match(status, /app\/web\/vendor\/three/);
  } finally {
    await browser.close();
    s.proc.kill('SIGINT');
    await s.exited;
  }
});

// The page's three.js (app/web/vendor/three, what every build stages and serves) is byte for byte
// the release whose own code these tests run (tests/engines' package-lock), and the build served
// it: the page is tested as it ships.
test('the page serves the three.js the tests run', async () => {
  const here = (p) => fileURLToPath(new URL(p, import.meta.url));
  const s = serve(['synthetic:64x32', '--headless', '--size', '32x18', '--duration', '60', '--serve', '0',
                   '--quiet']);
  try {
    const port = await s.port;
    for (const f of ['three.module.js', 'three.core.js']) {
      const vendored = readFileSync(here(`../../app/web/vendor/three/${f}`));
      assert.ok(vendored.equals(readFileSync(here(`node_modules/three/build/${f}`))),
                `app/web/vendor/three/${f} is tests/engines' three.js`);
      const served = Buffer.from(await (await fetch(`http://127.0.0.1:${port}/three/${f}`)).arrayBuffer());
      assert.ok(served.equals(vendored), `/three/${f} is the vendored file`);
    }
  } finally {
    s.proc.kill('SIGINT');
    await s.exited;
  }
});
