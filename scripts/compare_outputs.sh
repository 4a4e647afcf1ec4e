#!/usr/bin/env bash
# Writes the PRISM, JANI and DOT output of every example into DIR, so that two trees'
# outputs can be compared byte for byte (`diff -r`): a refactoring must not change them.
# Usage: bash scripts/compare_outputs.sh DIR
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: compare_outputs.sh DIR}
mkdir -p "$out"
for f in examples/*.afsm; do
    name=$(basename "$f" .afsm)
    for t in prism jani dot; do
        # the diagnostics too, without the output folder's name (which differs by run)
        .venv/bin/afsmc compile "$f" -t "$t" -o "$out/$name" 2>&1 >/dev/null \
            | sed "s|$out/||g" >"$out/$name.$t.err" || true
    done
done
echo "wrote $(find "$out" -type f | wc -l) files to $out"
