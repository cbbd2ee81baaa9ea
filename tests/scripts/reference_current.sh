#!/usr/bin/env bash
# The checked-in command reference and man page are what the declarations generate now; the man
# page renders without a groff warning, and its examples are the manual's; the bash completion
# completes commands and options.
# Usage: reference_current.sh DOCS_DIR LIVEPROBE_DOCS
set -uo pipefail
docs=$1 gen=$2
fail() { echo "FAIL: $*" >&2; exit 1; }
diff -u "$docs/reference.md" <("$gen" markdown) ||
  fail "docs/reference.md differs from the declarations: run scripts/reference"
diff -u "$docs/liveprobe.1" <("$gen" man) ||
  fail "docs/liveprobe.1 differs from the declarations: run scripts/reference"
warnings=$(MANWIDTH=100 man --warnings=all -l "$docs/liveprobe.1" 2>&1 >/dev/null)
[[ -z $warnings ]] || fail "man reports: $warnings"
page=$(MANWIDTH=100 man -l "$docs/liveprobe.1" 2>/dev/null)
grep -q -- "--window none|auto|cmgen|W" <<<"$page" || fail "the rendered page lacks --window"
# Every example of the page is one the manual gives (where the test suite runs it as written).
examples=$(awk '/^EXAMPLES/ {on = 1; next} /^[A-Z]/ {on = 0} on && /^ +liveprobe / {sub(/^ +/, ""); print}' <<<"$page")
[[ -n $examples ]] || fail "the rendered page has no EXAMPLES"
while IFS= read -r example; do
  grep -qF -- "$example" "$docs/../README.md" "$docs"/*.md ||
    fail "the man page's example is in neither README.md nor docs/: $example"
done <<<"$examples"
source <("$gen" bash)
COMP_WORDS=(liveprobe coe) COMP_CWORD=1
_liveprobe
[[ ${COMPREPLY[*]} == coeffs ]] || fail "'liveprobe coe' completes to '${COMPREPLY[*]}'"
COMP_WORDS=(liveprobe replay --out-v) COMP_CWORD=2 COMPREPLY=()
_liveprobe
[[ ${COMPREPLY[*]} == --out-video ]] || fail "'replay --out-v' completes to '${COMPREPLY[*]}'"
COMP_WORDS=(liveprobe coeffs --out-v) COMP_CWORD=2 COMPREPLY=()
_liveprobe
[[ -z ${COMPREPLY[*]} ]] || fail "coeffs has no --out-video, yet it completes to '${COMPREPLY[*]}'"
echo "reference, man page and completion are current"
