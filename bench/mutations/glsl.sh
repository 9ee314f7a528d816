#!/usr/bin/env bash
# Hand mutations of the GLSL, each with the test that must catch it: applies
# them one by one to a scratch copy of the tree (never to this checkout),
# builds it against this checkout's target directory (so shaderc is not
# rebuilt) and runs the named test (crate: a folder of tests/, e.g. report; filter:
# module::test). Prints one line per mutation: caught
# (the test failed, as it must) or MISSED; exits 1 if any was missed.
# Usage: bash bench/mutations/glsl.sh [NAME_FILTER]
# The list: bench/mutations/glsl.txt, one mutation a line:
#   name | file | sed expression (applied once, must change the file) | test crate | test filter
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$PWD
filter=${1:-}
scratch=$(mktemp -d)
# The scratch builds share this checkout's target directory, so they also
# replace its target/debug/hybrid-rt: touching src/lib.rs on the way out
# makes the next build of this checkout link its own again.
trap 'rm -rf "$scratch"; touch "$root/src/lib.rs"' EXIT
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$root/target}
missed=0
while IFS='|' read -r name file expr crate test; do
  # Comments first: xargs below chokes on their apostrophes.
  [[ "$name" =~ ^[[:space:]]*(#|$) ]] && continue
  name=$(echo "$name" | xargs); file=$(echo "$file" | xargs); crate=$(echo "$crate" | xargs)
  test=$(echo "$test" | xargs); expr=$(echo "$expr" | sed 's/^ *//; s/ *$//')
  [[ -z "$name" || "$name" == \#* ]] && continue
  [[ -n "$filter" && "$name" != *"$filter"* ]] && continue
  # A "|" inside the sed expression would shift the fields: refuse the line.
  if [[ -z "$crate" || -z "$test" || "$test" == *"|"* ]]; then
    echo "$name: malformed line (five fields separated by |; no | inside the expression)"; missed=1; continue
  fi
  rm -rf "$scratch/tree" && mkdir -p "$scratch/tree"
  git ls-files -z --cached --others --exclude-standard | xargs -0 cp --parents -t "$scratch/tree"
  ln -s "$root/../shared" "$scratch/shared" 2>/dev/null || true
  before=$(md5sum "$scratch/tree/$file")
  sed -i "$expr" "$scratch/tree/$file"
  if [ "$before" = "$(md5sum "$scratch/tree/$file")" ]; then
    echo "$name: the expression did not change $file (stale mutation)"; missed=1; continue
  fi
  if (cd "$scratch/tree" && cargo test --locked --test "$crate" -- --test-threads 2 "$test" >"$scratch/log" 2>&1); then
    echo "$name: MISSED ($crate $test passed with $file mutated)"; missed=1
  else
    if grep -q "error\[E\|error: could not compile\|shader compilation failed" "$scratch/log"; then
      echo "$name: did not build (not a mutant the test saw)"; missed=1
    else
      echo "$name: caught by $crate $test ($(grep -m1 -o 'panicked at [^:]*:[0-9]*' "$scratch/log" || true))"
    fi
  fi
done < bench/mutations/glsl.txt
exit "$missed"
