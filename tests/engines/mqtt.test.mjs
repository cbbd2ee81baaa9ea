// --publish against a real mosquitto broker (Debian's), started by the test on a free loopback
// port: mosquitto_sub receives every frame, each the matching --coeffs-out line; a subscriber
// that comes late gets the retained last frame; a broker killed and restarted mid-run neither
// stalls nor stops capture, publishing resumes, and the lost messages are counted.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { createServer } from 'node:net';
import { tmpdir, userInfo } from 'node:os';
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
/// `extra`: more configuration lines; `pubArgs`: what mosquitto_pub needs to reach it. Started as
/// root, mosquitto would drop to its own user, who cannot read this test's private files. A busy
/// machine can take seconds to start it (a TLS handshake is costly): the wait is 60 s, and a
/// broker that exits says why.
async function broker(port, extra = '', pubArgs = ['-h', '127.0.0.1']) {
  const conf = join(dir, `mosquitto-${port}.conf`);
  writeFileSync(conf, `listener ${port} ${extra.includes('certfile') ? '' : '127.0.0.1'}\n` +
                      `${extra || 'allow_anonymous true\n'}persistence false\nuser ${userInfo().username}\n`);
  const proc = spawn('mosquitto', ['-c', conf], { stdio: ['ignore', 'ignore', 'pipe'] });
  let said = '', exited = null;
  proc.stderr.on('data', (d) => (said += d));
  brokers.add(proc);
  proc.on('exit', (code, signal) => { exited = code ?? signal; brokers.delete(proc); });
  for (const deadline = Date.now() + 60000; Date.now() < deadline && exited === null;) {
    const r = spawnSync('mosquitto_pub', [...pubArgs, '-p', String(port), '-t', 'ping', '-m', 'x'], { timeout: 10000 });
    if (r.status === 0) return proc;
    await sleep(100);
  }
  throw new Error(exited === null ? `mosquitto on port ${port} accepted nothing in 60 s`
                                  : `mosquitto on port ${port} exited (${exited}): ${said.trim()}`);
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
  const before = (await subscribe(port, topic, 1))[0].frame;  // the last frame before the kill
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
  // New ones: past the last frame before the kill by at least a second of the 3 s the broker
  // was down (counted from liveprobe's frames, not the clock: a busy machine starts it late).
  assert.ok(resumed[0].frame > before + 30,
            `the frames after the restart are new ones: ${resumed[0].frame} after ${before}`);
});

const replayArgs = ['synthetic:64x32@30', '--headless', '--size', '64x36', '--frames', '20', '--quiet'];

test('a broker that wants a user and password: from the URL, the environment or a file; refused in one line', async () => {
  const port = await freePort();
  const passwd = join(dir, 'passwd');
  assert.equal(spawnSync('mosquitto_passwd', ['-c', '-b', passwd, 'studio', 's3cret']).status, 0);
  await broker(port, `allow_anonymous false\npassword_file ${passwd}\n`,
               ['-h', '127.0.0.1', '-u', 'studio', '-P', 's3cret']);
  const pwFile = join(dir, 'pw.txt');
  writeFileSync(pwFile, 's3cret\n');
  for (const [url, extra, env] of [[`mqtt://studio:s3cret@127.0.0.1:${port}/lp/a`, [], {}],
                                   [`mqtt://studio@127.0.0.1:${port}/lp/a`, [], { LIVEPROBE_MQTT_PASSWORD: 's3cret' }],
                                   [`mqtt://studio@127.0.0.1:${port}/lp/a`, ['--mqtt-password-file', pwFile], {}]]) {
    const r = spawnSync(liveprobe, ['replay', ...replayArgs, '--publish', url, ...extra],
                        { encoding: 'utf8', env: { ...process.env, ...env } });
    assert.equal(r.status, 0, r.stderr);
    assert.match(r.stderr, /mqtt:\/\/studio@127\.0\.0\.1:\d+\/lp\/a: 20 published, 0 lost/);
    assert.doesNotMatch(r.stderr, /s3cret/, 'the password is never echoed');
  }
  const r = spawnSync(liveprobe, ['replay', ...replayArgs, '--publish', `mqtt://studio:wrong@127.0.0.1:${port}/lp/a`],
                      { encoding: 'utf8' });
  assert.equal(r.status, 1, r.stderr);
  assert.equal(r.stderr.trim().split('\n').length, 1, r.stderr);
  assert.match(r.stderr, /mqtt:\/\/studio@127\.0\.0\.1:\d+\/lp\/a: the broker refused the connection/);
  assert.doesNotMatch(r.stderr, /wrong/);
});

test('mqtts:// checks the broker against --mqtt-cafile; a broker it cannot trust gets nothing, exit 3', async () => {
  const port = await freePort();
  const ca = join(dir, 'ca'), srv = join(dir, 'srv');
  const ssl = (args) => assert.equal(spawnSync('openssl', args, { stdio: 'ignore' }).status, 0, args.join(' '));
  ssl(['req', '-x509', '-newkey', 'rsa:2048', '-nodes', '-days', '2', '-subj', '/CN=liveprobe test CA',
       '-keyout', `${ca}.key`, '-out', `${ca}.pem`]);
  ssl(['req', '-newkey', 'rsa:2048', '-nodes', '-subj', '/CN=localhost', '-keyout', `${srv}.key`, '-out', `${srv}.csr`]);
  writeFileSync(`${srv}.ext`, 'subjectAltName=DNS:localhost,IP:127.0.0.1\n');
  ssl(['x509', '-req', '-in', `${srv}.csr`, '-CA', `${ca}.pem`, '-CAkey', `${ca}.key`, '-CAcreateserial', '-days', '2',
       '-extfile', `${srv}.ext`, '-out', `${srv}.pem`]);
  await broker(port, `allow_anonymous true\ncafile ${ca}.pem\ncertfile ${srv}.pem\nkeyfile ${srv}.key\n`,
               ['-h', 'localhost', '--cafile', `${ca}.pem`]);
  const ok = spawnSync(liveprobe, ['replay', ...replayArgs, '--publish', `mqtts://localhost:${port}/lp/tls`,
                                   '--mqtt-cafile', `${ca}.pem`], { encoding: 'utf8' });
  assert.equal(ok.status, 0, ok.stderr);
  assert.match(ok.stderr, /mqtts:\/\/localhost:\d+\/lp\/tls: 20 published, 0 lost/);
  // Without the CA the system's store does not trust this broker: nothing is sent, and the
  // run says so at start, in its summary and in its exit status.
  const bad = spawnSync(liveprobe, ['replay', ...replayArgs, '--publish', `mqtts://localhost:${port}/lp/tls`],
                        { encoding: 'utf8' });
  assert.equal(bad.status, 3, bad.stderr);
  assert.match(bad.stderr, /warning: mqtts:\/\/localhost:\d+\/lp\/tls: no broker answers yet/);
  assert.match(bad.stderr, /0 published, 20 lost .*; no message reached the broker/);
});

test('no broker at all: said at start, and exit 3 with nothing published', async () => {
  const port = await freePort();
  const r = spawnSync(liveprobe, ['replay', ...replayArgs, '--publish', `mqtt://127.0.0.1:${port}/lp/none`],
                      { encoding: 'utf8' });
  assert.equal(r.status, 3, r.stderr);
  // Nothing listens on the port: the connection is refused at once, and the run says so
  // without waiting out the 3 s it gives a broker that is slow to answer.
  assert.match(r.stderr.split('\n')[0],
               /warning: mqtt:\/\/127\.0\.0\.1:\d+\/lp\/none: no broker listens there \(connection refused\)/);
  assert.match(r.stderr, /no message reached the broker/);
});

test('topics MQTT cannot publish to are refused in one line, exit 1', () => {
  for (const [topic, says] of [['lp/#', /wildcards/], ['lp/+/x', /wildcards/], ['x'.repeat(70000), /65535/]]) {
    const r = spawnSync(liveprobe, ['replay', ...replayArgs, '--publish', `mqtt://127.0.0.1:1/${topic}`],
                        { encoding: 'utf8' });
    assert.equal(r.status, 1, r.stderr.slice(0, 200));
    assert.equal(r.stderr.trim().split('\n').length, 1);
    assert.match(r.stderr, says);
  }
  // Invalid UTF-8 cannot be a JavaScript string: the shell passes the byte.
  const r = spawnSync('bash', ['-c', `"$LP" replay ${replayArgs.join(' ')} --publish "mqtt://127.0.0.1:1/lp/$(printf '\\xff')"`],
                      { encoding: 'utf8', env: { ...process.env, LP: liveprobe } });
  assert.equal(r.status, 1, r.stderr);
  assert.match(r.stderr, /the topic is not valid UTF-8/);
  assert.equal(r.stderr.trim().split('\n').length, 1);
});
