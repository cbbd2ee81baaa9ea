// Starting `liveprobe replay --serve` for the stream and browser tests: the port it bound (it
// binds port 0, so the kernel picks a free loopback port), its stderr, and its end.
import { spawn } from 'node:child_process';
import { readFileSync, readdirSync } from 'node:fs';
import { liveprobe } from './common.mjs';

export function serve(args, extraEnv = {}) {
  // Under AddressSanitizer (scripts/test-sanitizers), freed memory waits in a quarantine that
  // would show as growth in the RSS checks: no quarantine there (LeakSanitizer checks leaks).
  const env = { ...process.env, ...extraEnv };
  if (env.ASAN_OPTIONS) env.ASAN_OPTIONS += ':quarantine_size_mb=0:thread_local_quarantine_size_kb=0';
  const proc = spawn(liveprobe, ['replay', ...args], { stdio: ['ignore', 'ignore', 'pipe'], env });
  let stderr = '';
  const exited = new Promise((resolve) => proc.on('exit', (code, signal) => resolve({ code, signal, stderr })));
  const port = new Promise((resolve, reject) => {
    proc.stderr.on('data', (d) => {
      stderr += d;
      const m = stderr.match(/serving http:\/\/127\.0\.0\.1:(\d+)\//);
      if (m) resolve(Number(m[1]));
    });
    exited.then((e) => reject(new Error(`liveprobe exited (${e.code}): ${stderr}`)));
  });
  return { proc, port, exited, stderr: () => stderr };
}

/// Resident memory (kB) and open file descriptors of a process, from /proc. `rss` is the
/// anonymous part (RssAnon: the heap and stacks, where anything held for clients lives); the
/// file-backed pages (code and data of the libraries, paged in as new paths first run) are `file`.
export function usage(pid) {
  const status = readFileSync(`/proc/${pid}/status`, 'utf8');
  const kb = (key) => Number(status.match(new RegExp(`${key}:\\s+(\\d+)`))[1]);
  return { rss: kb('RssAnon'), file: kb('RssFile'), fds: readdirSync(`/proc/${pid}/fd`).length };
}
