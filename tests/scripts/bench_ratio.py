#!/usr/bin/env python3
"""A timing check for CI, as a ratio measured in one run: liveprobe-bench's benchmarks matching
FILTER come in families .../BASE and .../OTHER; with the repetitions randomly interleaved (so a
slow moment of the machine falls on both), the median real time of each OTHER must be at most
LIMIT times its BASE's.

usage: bench_ratio.py LIVEPROBE_BENCH FILTER BASE OTHER LIMIT [REPETITIONS [MIN_TIME]]
"""
import json
import statistics
import subprocess
import sys


def main():
    bench, pattern, base, other, limit = sys.argv[1:6]
    reps = sys.argv[6] if len(sys.argv) > 6 else "7"
    min_time = sys.argv[7] if len(sys.argv) > 7 else "0.1"  # seconds of timing a repetition
    out = subprocess.run(
        [bench, "--benchmark_filter=" + pattern, "--benchmark_repetitions=" + reps,
         "--benchmark_enable_random_interleaving=true", "--benchmark_min_time=" + min_time,
         "--benchmark_format=json"],
        check=True, capture_output=True, text=True).stdout
    times = {}
    for b in json.loads(out)["benchmarks"]:
        if b.get("run_type") == "iteration":
            name = b["run_name"].removesuffix("/real_time")  # UseRealTime() names
            times.setdefault(name, []).append(b["real_time"])
    suffix = "/" + other
    pairs = [(name[: -len(suffix)] + "/" + base, name) for name in times if name.endswith(suffix)]
    if not pairs:
        sys.exit(f"bench_ratio: no benchmarks .../{other} match {pattern}")
    failed = False
    for plain, more in sorted(pairs):
        if plain not in times:
            sys.exit(f"bench_ratio: {more} has no {plain} to compare with")
        a, b = statistics.median(times[plain]), statistics.median(times[more])
        ok = b <= float(limit) * a
        failed |= not ok
        print(f"{'ok  ' if ok else 'FAIL'} {more}: {b:.0f} against {base} {a:.0f} us, "
              f"x{b / a:.3f} (limit x{float(limit):.2f})")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
