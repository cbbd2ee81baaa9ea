// The live stream (replay --serve) against a real WebSocket client (npm ws): order and content,
// latest-value semantics for a client that reads nothing, 50 clients coming and going, bad
// client frames, the loopback-only default, and a clean close at the end. Everything binds to
// 127.0.0.1 and ends by itself.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import WebSocket from 'ws';
import { run, liveprobe } from './common.mjs';
import { serve, usage } from './serve.mjs';
import { spawnSync } from 'node:child_process';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// The most the server's anonymous memory may grow over a run (kB): 4 MB, or 16 MB under
// AddressSanitizer (scripts/test-sanitizers), whose allocator and shadow memory grow it by 4.6 to
// 4.8 MB on their own there (the normal build: 0.3 to 0.7 MB); LeakSanitizer checks leaks there.
const kGrowthKb = process.env.ASAN_OPTIONS ? 16384 : 4096;

/// Opens a client; resolves when open. Collects messages and the close code.
function client(port, query = '') {
  const ws = new WebSocket(`ws://127.0.0.1:${port}/${query}`);
  const c = { ws, messages: [], closed: null };
  ws.on('message', (d, binary) => c.messages.push(JSON.parse(String(d))));
  c.closedP = new Promise((resolve) => ws.on('close', (code, reason) => resolve(c.closed = { code, reason: String(reason) })));
  c.open = new Promise((resolve, reject) => { ws.on('open', resolve); ws.on('error', reject); });
  return c;
}

/// A record without what only --coeffs-out knows after drawing (the render time and the
/// latency to the shown frame): the stream sends at capture.
function captured(r) {
  const { timings_ms: { render, ...timings }, latency_ms: { shown, ...latency }, ...rest } = r;
  return { ...rest, timings, latency };
}

test('a client receives every frame in order, each the matching --coeffs-out line', async () => {
  const dir = mkdtempSync(join(tmpdir(), 'lp-stream-'));
  const out = join(dir, 'c.jsonl');
  const s = serve(['synthetic:128x64@30', '--headless', '--size', '64x36', '--frames', '90', '--serve', '0',
                   '--coeffs-out', out, '--coeffs-format', 'babylon', '--sun', '--quiet']);
  const c = client(await s.port, '?format=babylon');
  await c.open;
  const close = await c.closedP;
  const end = await s.exited;
  assert.equal(end.code, 0, end.stderr);
  assert.equal(close.code, 1001, 'a clean close (going away) when liveprobe stops');
  const lines = readFileSync(out, 'utf8').trim().split('\n').map((l) => JSON.parse(l));
  assert.equal(lines.length, 90);
  const frames = c.messages.map((m) => m.frame);
  console.log(`received ${frames.length} of 90 frames, from ${frames[0]} to ${frames.at(-1)}`);
  // Most frames arrive; on a busy machine (the suite beside stress-ng) some are superseded before
  // they go out, and the summary counts them (below).
  assert.ok(frames.length >= 60, `${frames.length} messages`);
  // In order, never repeated; a frame the client missed on a busy machine (the stream sends the
  // newest, never a queue) is one the summary counts as dropped.
  for (let i = 1; i < frames.length; ++i) assert.ok(frames[i] > frames[i - 1], 'in order, never repeated');
  const missed = frames.at(-1) - frames[0] + 1 - frames.length;
  const dropped = Number(end.stderr.match(/(\d+) dropped for slow clients/)[1]);
  assert.ok(missed <= dropped, `${missed} frames missed, ${dropped} counted as dropped`);
  for (const m of c.messages) {
    assert.equal(m.format, 'babylon');
    assert.deepEqual(captured(m), captured(lines[m.frame]));
  }
});

test('a headless replay stopped by Ctrl-C logs every record it sent', async () => {
  const dir = mkdtempSync(join(tmpdir(), 'lp-stream-'));
  const out = join(dir, 'c.jsonl');
  // Paced at 10 frames/s: a stop lands while a sent frame waits to be drawn.
  const s = serve(['synthetic:128x64@10', '--headless', '--size', '64x36', '--serve', '0',
                   '--coeffs-out', out, '--quiet']);
  const c = client(await s.port, '?format=json');
  await c.open;
  while (c.messages.length < 12) await sleep(20);
  s.proc.kill('SIGINT');
  const end = await s.exited;
  assert.equal(end.code, 130, end.stderr);
  await c.closedP;
  const logged = new Map(readFileSync(out, 'utf8').trim().split('\n').map((l) => JSON.parse(l)).map((r) => [r.frame, r]));
  const last = c.messages.at(-1);
  console.log(`${c.messages.length} frames sent, the last ${last.frame}; ${logged.size} logged`);
  for (const m of c.messages) {
    assert.ok(logged.has(m.frame), `frame ${m.frame} was sent but is not in --coeffs-out`);
    assert.deepEqual(captured(m), captured(logged.get(m.frame)));
  }
});

test('a client that reads nothing for 10 s slows nothing and grows no memory', async () => {
  const s = serve(['synthetic:256x128@60', '--headless', '--size', '64x36', '--duration', '13',
                   '--serve', '0', '--quiet']);
  const port = await s.port;
  const slow = client(port);
  await slow.open;
  slow.ws._socket.pause();  // reads nothing from here on
  const fast = client(port);
  const arrivals = [];
  fast.ws.on('message', () => arrivals.push(Date.now()));
  await fast.open;
  await sleep(2000);
  const before = usage(s.proc.pid), from = Date.now();
  await sleep(9000);
  const after = usage(s.proc.pid), to = Date.now();
  const fastCount = fast.messages.length;
  // The longest wait of the reading client between two frames while the silent one held its
  // socket full (the edges of the window count as arrivals).
  const times = [from, ...arrivals.filter((t) => t > from && t < to), to];
  const longestGap = Math.max(...times.slice(1).map((t, i) => t - times[i]));
  const frames = fast.messages.map((m) => m.frame);
  const end = await s.exited;
  assert.equal(end.code, 0, end.stderr);
  const captured = Number(end.stderr.match(/(\d+) frames captured/)[1]);
  const dropped = Number(end.stderr.match(/(\d+) dropped for slow clients/)[1]);
  console.log(`captured ${captured} frames in 13 s; the reading client got ${fastCount}, ` +
              `at most ${longestGap} ms apart; ${dropped} dropped for the slow one; ` +
              `anonymous memory ${before.rss} -> ${after.rss} kB (file-backed ${before.file} -> ${after.file})`);
  // What is asserted is that the silent client blocks neither capture nor the reading client:
  // capture keeps its rate (a margin a loaded machine does not cross), and the reading client gets
  // newer and newer frames all along (how many depends on the CPU its own process gets: the
  // latest-value stream skips what it has no time to read; a server stuck writing to the silent
  // client would send it nothing for seconds).
  assert.ok(captured >= 13 * 60 * 0.75, `capture held its rate: ${captured}`);
  assert.ok(frames.every((f, i) => i === 0 || f > frames[i - 1]), 'frames in order, never repeated');
  assert.ok(longestGap < 2000, `the reading client waited ${longestGap} ms for a frame`);
  assert.ok(dropped > 100, `the slow client's frames were dropped, not queued: ${dropped}`);
  assert.ok(after.rss - before.rss < kGrowthKb, `anonymous memory grew ${after.rss - before.rss} kB`);
});

test('50 clients connecting and disconnecting for 30 s leak nothing', async () => {
  const s = serve(['synthetic:128x64@30', '--headless', '--size', '64x36', '--duration', '40',
                   '--serve', '0', '--serve-clients', '64', '--quiet']);
  const port = await s.port;
  await sleep(1000);
  const before = usage(s.proc.pid);
  const t0 = Date.now();
  let rounds = 0;
  while (Date.now() - t0 < 30000) {
    const clients = Array.from({ length: 50 }, () => client(port));
    await Promise.all(clients.map((c) => c.open));
    await sleep(100);
    clients.forEach((c) => c.ws.close());
    await Promise.all(clients.map((c) => c.closedP));
    ++rounds;
  }
  await sleep(500);
  const after = usage(s.proc.pid);
  s.proc.kill('SIGINT');
  const end = await s.exited;
  const served = Number(end.stderr.match(/(\d+) clients served/)[1]);
  console.log(`${rounds} rounds, ${served} clients served; fds ${before.fds} -> ${after.fds}; ` +
              `anonymous memory ${before.rss} -> ${after.rss} kB (file-backed ${before.file} -> ${after.file})`);
  assert.equal(served, rounds * 50);
  assert.equal(after.fds, before.fds, 'every connection closed its descriptor');
  assert.ok(after.rss - before.rss < kGrowthKb, `anonymous memory grew ${after.rss - before.rss} kB`);
});

test('malformed, oversized and binary client frames close that client only', async () => {
  const s = serve(['synthetic:128x64@30', '--headless', '--size', '64x36', '--duration', '6',
                   '--serve', '0', '--quiet']);
  const port = await s.port;
  const good = client(port), bad = [client(port), client(port), client(port), client(port)];
  await Promise.all([good.open, ...bad.map((c) => c.open)]);
  bad[0].ws.send('{"format": ');                          // not JSON
  bad[1].ws.send('x'.repeat(64 * 1024));                 // over the 4 KiB a client may send
  bad[2].ws.send(Buffer.from([1, 2, 3]), { binary: true });
  bad[3].ws.send('{"format": "povray"}');                // no such format
  const codes = (await Promise.all(bad.map((c) => c.closedP))).map((c) => c.code);
  console.log(`close codes: ${codes.join(', ')}`);
  assert.deepEqual(codes, [1007, 1009, 1003, 1007]);
  const n = good.messages.length;
  good.ws.send('{"format": "filament"}');                // a good message: the format changes
  await sleep(500);
  assert.ok(good.messages.length > n, 'the good client still receives');
  assert.ok(good.messages.at(-1).coefficients.irradiance, 'in the format it asked for');
  await good.closedP;
  const end = await s.exited;
  assert.equal(end.code, 0, end.stderr);
  assert.match(end.stderr, / 4 closed \(bad message or idle\)/);
});

test('an unknown format in the query closes with a reason; the client limit refuses', async () => {
  const s = serve(['synthetic:128x64@30', '--headless', '--size', '64x36', '--duration', '4',
                   '--serve', '0', '--serve-clients', '2', '--quiet']);
  const port = await s.port;
  const q = client(port, '?format=povray');
  const closed = await q.closedP;
  assert.equal(closed.code, 1008);
  assert.match(closed.reason, /povray/);
  // The query is read strictly: a 4 KB one, another key, a repeated format (1008 with the
  // reason); a broken %-escape is refused by lws before the upgrade (HTTP 403).
  const broken = new WebSocket(`ws://127.0.0.1:${port}/?format=thr%4`);
  const status = await new Promise((resolve) => {
    broken.on('unexpected-response', (req, res) => resolve(res.statusCode));
    broken.on('error', () => {});
    broken.on('open', () => resolve('open'));
  });
  assert.equal(status, 403, 'a broken %-escape is not taken as a format');
  broken.terminate();
  for (const [query, reason] of [[`?format=three&pad=${'x'.repeat(4096)}`, /query of \d+ bytes/],
                                 ['?colour=red', /expected format=NAME/],
                                 ['?format=three&format=babylon', /twice/]]) {
    const bad = client(port, query);
    bad.open.catch(() => {});
    const why = await bad.closedP;
    assert.equal(why.code, 1008, query.slice(0, 40));
    assert.match(why.reason, reason, query.slice(0, 40));
  }
  await sleep(300);  // the server has seen them go
  const a = client(port), b = client(port);
  await Promise.all([a.open, b.open]);
  const c = client(port);
  await assert.rejects(c.open, /socket hang up|Unexpected server response/);
  const end = await s.exited;
  assert.match(end.stderr, / 1 refused \(client limit\)/);
});

test('a client that answers no ping for --serve-idle seconds is closed, freeing its place', async () => {
  const s = serve(['synthetic:128x64@30', '--headless', '--size', '64x36', '--duration', '8',
                   '--serve', '0', '--serve-clients', '1', '--serve-idle', '2', '--quiet']);
  const port = await s.port;
  const silent = client(port);
  await silent.open;
  silent.ws._socket.pause();  // reads nothing, so it answers no ping
  const early = client(port);
  await assert.rejects(early.open, /socket hang up|Unexpected server response/, 'the one place is taken');
  await sleep(4000);
  const late = client(port);
  await late.open;  // the silent client was hung up after 2 s
  await late.closedP;
  const end = await s.exited;
  assert.equal(end.code, 0, end.stderr);
});

test('an address this machine does not have is one line, never "serving"', () => {
  const r = spawnSync(liveprobe, ['replay', 'synthetic:64x32', '--headless', '--frames', '1', '--serve',
                                  '192.0.2.1:0', '--serve-remote'], { encoding: 'utf8' });
  assert.equal(r.status, 1);
  assert.match(r.stderr, /--serve 192\.0\.2\.1:0: 192\.0\.2\.1 is not an address of this machine/);
  assert.doesNotMatch(r.stderr, /serving/);
  assert.equal(r.stderr.trim().split('\n').length, 1, 'one line');
});

test('listening beyond the loopback must be asked for', () => {
  const r = spawnSync(liveprobe, ['replay', 'synthetic:64x32', '--headless', '--frames', '1', '--serve', '0.0.0.0:0'],
                      { encoding: 'utf8' });
  assert.notEqual(r.status, 0);
  assert.match(r.stderr, /--serve 0\.0\.0\.0:0: 0\.0\.0\.0 is reachable from other machines; add --serve-remote/);
  assert.equal(r.stderr.trim().split('\n').length, 1, 'one line');
});
