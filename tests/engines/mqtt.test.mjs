// --publish against a real mosquitto broker (Debian's), started by the test on a free loopback
// port: mosquitto_sub receives every frame, each the matching --coeffs-out line; a subscriber
// that comes late gets the retained last frame; a broker killed and restarted mid-run neither
// stalls nor stops capture, publishing resumes, and the lost messages are counted.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { createServer } from 'node:net';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { liveprobe } from './common.mjs';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const dir = mkdtempSync(join(tmpdir(), 'lp-mqtt-'));
const brokers = new Set();

function freePort() {
  return new Promise((resolve) => {
    const s = createServer();
    s.listen(0, '127.0.0.1', () => { const p = s.address().port; s.close(() => resolve(p)); });
  });
}

/// A mosquitto listening on 127.0.0.1:port only, no persistence; resolves once it accepts.
async function broker(port) {
  const conf = join(dir, `mosquitto-${port}.conf`);
  writeFileSync(conf, `listener ${port} 127.0.0.1\nallow_anonymous true\npersistence false\n`);
  const proc = spawn('mosquitto', ['-c', conf], { stdio: 'ignore' });
  brokers.add(proc);
  proc.on('exit', () => brokers.delete(proc));
  for (let i = 0; i < 100; ++i) {
    const r = spawnSync('mosquitto_pub', ['-h', '127.0.0.1', '-p', String(port), '-t', 'ping', '-m', 'x']);
    if (r.status === 0) return proc;
    await sleep(50);
  }
  throw new Error('mosquitto did not start');
}
after(() => { for (const b of brokers) b.kill('SIGKILL'); });

/// mosquitto_sub collecting messages of a topic (-C: stop after that many).
function subscribe(port, topic, count) {
  const proc = spawn('mosquitto_sub', ['-h', '127.0.0.1', '-p', String(port), '-t', topic, '-C', String(count), '-W', '60'],
                     { stdio: ['ignore', 'pipe', 'inherit'] });
  let out = '';
  proc.stdout.on('data', (d) => (out += d));
  return new Promise((resolve) => proc.on('exit', () => resolve(out.trim().split('\n').filter(Boolean).map((l) => JSON.parse(l)))));
}

function runLiveprobe(args) {
  const proc = spawn(liveprobe, ['replay', ...args], { stdio: ['ignore', 'ignore', 'pipe'] });
  let stderr = '';
  proc.stderr.on('data', (d) => (stderr += d));
  return new Promise((resolve) => proc.on('exit', (code) => resolve({ code, stderr })));
}

function captured(r) {
  const { timings_ms: { render, ...timings }, latency_ms: { shown, ...latency }, ...rest } = r;
  return { ...rest, timings, latency };
}

test('mosquitto_sub receives every frame, each the matching --coeffs-out line; late subscribers get the last', async () => {
  const port = await freePort();
  await broker(port);
  const topic = 'liveprobe/test';
  const got = subscribe(port, topic, 60);
  await sleep(300);  // subscribed
  const out = join(dir, 'c.jsonl');
  const r = await runLiveprobe(['synthetic:128x64@30', '--headless', '--size', '64x36', '--frames', '60', '--quiet',
                                '--publish', `mqtt://127.0.0.1:${port}/${topic}`, '--coeffs-out', out, '--coeffs-format', 'three']);
  assert.equal(r.code, 0, r.stderr);
  const messages = await got;
  const lines = readFileSync(out, 'utf8').trim().split('\n').map((l) => JSON.parse(l));
  assert.equal(messages.length, 60);
  messages.forEach((m, i) => assert.deepEqual(captured(m), captured(lines[i])));
  assert.match(r.stderr, /60 published, 0 lost/);
  const late = await subscribe(port, topic, 1);  // after the run: the retained message
  assert.deepEqual(captured(late[0]), captured(lines[59]));
});

test('a broker killed and restarted mid-run: capture goes on, publishing resumes, losses are counted', async () => {
  const port = await freePort();
  let b = await broker(port);
  const topic = 'liveprobe/restart';
  const run = runLiveprobe(['synthetic:128x64@30', '--headless', '--size', '64x36', '--duration', '12', '--quiet',
                            '--publish', `mqtt://127.0.0.1:${port}/${topic}`]);
  await sleep(3000);
  b.kill('SIGKILL');
  await sleep(3000);
  b = await broker(port);
  const resumed = await subscribe(port, topic, 5);  // new frames after the restart
  const r = await run;
  assert.equal(r.code, 0, r.stderr);
  const capturedFrames = Number(r.stderr.match(/(\d+) frames captured/)[1]);
  const m = r.stderr.match(/(\d+) published, (\d+) lost \(no broker connection\), (\d+) reconnects/);
  const [published, lost, reconnects] = m.slice(1).map(Number);
  console.log(`captured ${capturedFrames}; published ${published}, lost ${lost}, reconnects ${reconnects}; ` +
              `after the restart a subscriber got frames ${resumed.map((x) => x.frame).join(', ')}`);
  assert.ok(capturedFrames >= 12 * 30 * 0.95, `capture held its rate: ${capturedFrames}`);
  assert.ok(lost >= 30, `about 3 s of frames lost: ${lost}`);
  assert.ok(reconnects >= 1);
  assert.equal(published + lost, capturedFrames);
  assert.equal(resumed.length, 5);
  assert.ok(resumed[0].frame > 6 * 30 * 0.9, 'the frames after the restart are new ones');
});
