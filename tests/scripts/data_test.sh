#!/usr/bin/env bash
# scripts/data against a mirror (the suite's own data folder): every file of the manifest comes
# with its SHA-256 checked; a second run keeps them all; a mirror with one corrupted file gets that
# file refused in one line naming it, and nothing of it (nor a partial file) is left in place; a
# clone with nothing beside it reads the data from its own data/ once fetched.
set -euo pipefail
root=$1 mirror=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
files=$(grep -cv '^#' "$root/scripts/data.manifest")
out=$("$root/scripts/data" --from "$mirror" --to "$tmp/data" 2>&1) || fail "fetch from $mirror: $out"
[[ $out == *": $files fetched, 0 already there and right, 0 refused" ]] || fail "$out"
while IFS=$'\t' read -r sha bytes path _; do
  [[ $sha == \#* ]] && continue
  [[ $(sha256sum < "$tmp/data/$path" | cut -c1-64) == "$sha" ]] || fail "$path differs"
  [[ $(stat -c %s "$tmp/data/$path") == "$bytes" ]] || fail "$path is not $bytes bytes"
done < "$root/scripts/data.manifest"
out=$("$root/scripts/data" --from "$mirror" --to "$tmp/data" 2>&1) || fail "second run: $out"
[[ $out == *": 0 fetched, $files already there and right, 0 refused" ]] || fail "$out"
# A corrupted mirror: one byte of the teapot changed.
cp -r "$mirror" "$tmp/bad"
chmod -R u+w "$tmp/bad"
printf 'X' | dd of="$tmp/bad/models/teapot.obj" bs=1 seek=100 conv=notrunc 2> /dev/null
rm "$tmp/data/models/teapot.obj"
if out=$("$root/scripts/data" --from "$tmp/bad" --to "$tmp/data" 2>&1); then
  fail "a corrupted file was taken: $out"
fi
[[ $(grep -c ': refused$' <<< "$out") == 1 ]] || fail "not one refusal: $out"
grep -q '^scripts/data: models/teapot.obj: SHA-256 .* expected 1b5396fe.*: refused$' <<< "$out" ||
  fail "the refusal names no file: $out"
[[ ! -e $tmp/data/models/teapot.obj ]] || fail "the corrupted teapot was left in place"
[[ -z $(find "$tmp/data" -name '*.part.*') ]] || fail "a partial file was left"
# A mirror that is not there is one line, and exit 1.
if out=$("$root/scripts/data" --from "$tmp/none" --to "$tmp/x" 2>&1); then fail "no mirror: exit 0"; fi
[[ $(wc -l <<< "$out") == 1 && $out == *"no such folder"* ]] || fail "$out"
# A clone with nothing beside it: --where names ../shared/data and fails until scripts/data has
# filled the clone's data/, then names that; CMake and the scripts read the folder it names.
mkdir -p "$tmp/alone/clone/scripts"
cp "$root/scripts/data" "$root/scripts/data.manifest" "$tmp/alone/clone/scripts/"
if out=$(LIVEPROBE_DATA_DIR= "$tmp/alone/clone/scripts/data" --where); then fail "--where with no data: exit 0 ($out)"; fi
[[ $out == "$tmp/alone/shared/data" ]] || fail "--where with no data names $out"
"$tmp/alone/clone/scripts/data" --from "$mirror" 2> /dev/null || fail "the clone's fetch"
out=$(LIVEPROBE_DATA_DIR= "$tmp/alone/clone/scripts/data" --where) || fail "--where after the fetch: $out"
[[ $out == "$tmp/alone/clone/data" ]] || fail "--where after the fetch names $out"
echo "scripts/data: $files files fetched and checked; a corrupted one refused; --where follows"
