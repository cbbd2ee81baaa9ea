#!/usr/bin/env bash
# An install stands alone: installed into a prefix that is then moved, liveprobe names neither the
# source tree nor the build tree, replays its bundled recording with no source given, and serves
# its web page and three.js (GET / and /three/three.module.js). Usage: moved_install.sh BUILD
# (Consumer.BuildsAgainstAnInstall installs the same build: the two never run at once.)
set -euo pipefail
build=$(cd "$1" && pwd)
src=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
pid=
trap '[[ -n $pid ]] && kill "$pid" 2>/dev/null; rm -rf "$work"' EXIT
# Building the program alone (as scripts/demo does) makes all its install takes: the generated
# man page and package changelog, removed here, come back with it.
rm -f "$build/share/man/man1/liveprobe.1.gz" "$build/package-doc/changelog.gz"
cmake --build "$build" --target liveprobe >/dev/null
cmake --install "$build" --prefix "$work/first" >/dev/null
mv "$work/first" "$work/moved"
lp=$work/moved/bin/liveprobe
# What the program itself holds, without its debug information (a RelWithDebInfo build's line
# tables name the source files, which is what they are for).
objcopy --strip-debug "$lp" "$work/program"
for tree in "$src" "$build"; do
  if grep -q -F -- "$tree" "$work/program"; then
    echo "moved_install: the installed program names $tree" >&2
    exit 1
  fi
done
cd "$work"
unset LIVEPROBE_DEFAULT_RECORDING LIVEPROBE_WEB_DIR
"$lp" replay --headless --frames 3 --size 64x36 --quiet >replay.log 2>&1 || {
  cat replay.log >&2
  exit 1
}
grep -q -F "$work/moved/share/liveprobe/recordings/sky.mkv" replay.log || {
  echo "moved_install: replay did not play the installed recording:" >&2
  cat replay.log >&2
  exit 1
}
"$lp" replay --headless --serve 127.0.0.1:0 --loop --size 64x36 --quiet >serve.log 2>&1 &
pid=$!
python3 - "$work/serve.log" <<'PY'
import re, sys, time, urllib.request
deadline = time.time() + 30
port = None
while time.time() < deadline and port is None:
    m = re.search(r"serving http://127\.0\.0\.1:(\d+)/", open(sys.argv[1]).read())
    port = m and m.group(1)
    time.sleep(0.1)
if not port:
    sys.exit("moved_install: the server did not say where it serves:\n" + open(sys.argv[1]).read())
page = urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=10).read().decode()
if "importmap" not in page:
    sys.exit("moved_install: GET / is not the page:\n" + page[:500])
three = urllib.request.urlopen(f"http://127.0.0.1:{port}/three/three.module.js", timeout=10).read()
if b"three.core.js" not in three:
    sys.exit("moved_install: GET /three/three.module.js is not three.js")
print(f"moved_install: served the page ({len(page)} bytes) and three.js ({len(three)} bytes)")
PY
