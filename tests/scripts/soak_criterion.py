#!/usr/bin/env python3
"""The soak's memory criterion (tests/scripts/soak.sh) against programs whose memory is known:
one that leaks at a steady rate fails it; one that grows early in the run and then holds (as
allocator arenas do when threads first contend), by 20 MB after the warm-up, passes it; so does
one that is flat. Each stands in for liveprobe for 8 s: it writes the --coeffs-out lines soak.sh
counts.
Usage: soak_criterion.py SOAK_SH"""
import os
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True

FAKE = r'''#!/usr/bin/env python3
import sys, time
args = sys.argv[1:]
frames = int(args[args.index("--frames") + 1])
out = args[args.index("--coeffs-out") + 1]
kind, seconds = "%s", %f
held = []
start = time.monotonic()
while (t := time.monotonic() - start) < seconds:
    if kind == "leak":          # 6 MB a second, all run long
        held.append(bytearray(b"x" * 600_000))
    elif kind == "steps" and seconds / 4 < t < seconds / 2:  # 20 MB after warm-up, then held
        held.append(bytearray(b"x" * 1_000_000))
    time.sleep(0.1)
with open(out, "w") as f:
    f.write("{}\n" * frames)
print("%%d frames captured, 0 drawn" %% frames)
'''


def run(soak, kind, seconds=8.0):
    with tempfile.TemporaryDirectory() as d:
        fake = os.path.join(d, "liveprobe")
        with open(fake, "w") as f:
            f.write(FAKE % (kind, seconds))
        os.chmod(fake, 0o755)
        r = subprocess.run([soak, fake, "10", "synthetic:8x4"], capture_output=True, text=True)
        return r.returncode, r.stdout + r.stderr


def main():
    soak = sys.argv[1]
    failures = []
    for kind, should_pass in (("flat", True), ("steps", True), ("leak", False)):
        code, out = run(soak, kind)
        verdict = "passes" if code == 0 else "fails"
        print(f"{kind}: soak.sh {verdict}\n  " + out.strip().replace("\n", "\n  "))
        if (code == 0) != should_pass:
            failures.append(f"{kind}: expected the soak to {'pass' if should_pass else 'fail'}")
        if not should_pass and "a leak" not in out:
            failures.append(f"{kind}: the failure does not name the leak")
    for f in failures:
        print("soak_criterion:", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
