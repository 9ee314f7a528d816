#!/usr/bin/env bash
# Prints the slowest test binaries of a `cargo test` log (libtest reports a
# time per binary; per test only "has been running for over 60 seconds",
# which is listed too), so CI time stays visible as tests are added.
# Usage: bash .ci/slowest-tests.sh LOG [N]
set -euo pipefail
log=$1
n=${2:-12}
echo "== slowest test binaries (wall seconds) =="
awk '
    /^ *Running / { name = ($2 == "unittests") ? $3 " (unit tests)" : $2 }
    /^ *Doc-tests / { name = "doc-tests " $2 }
    /^test result:/ {
        for (i = 1; i <= NF; i++) if ($i == "in") { t = $(i + 1); sub(/s$/, "", t); printf "%8.1f  %s\n", t, name }
    }
' "$log" | sort -rn | head -n "$n"
awk '/^ *Running |^test result:/ { if ($1 == "test") { for (i = 1; i <= NF; i++) if ($i == "in") { t = $(i + 1); sub(/s$/, "", t); s += t } } }
     END { printf "%8.1f  total in test binaries\n", s }' "$log"
if grep -q "has been running for over 60 seconds" "$log"; then
    echo "== tests over 60 s =="
    grep "has been running for over 60 seconds" "$log" | sed 's/^test \(.*\) has been running.*/  \1/'
fi
