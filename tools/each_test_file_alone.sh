#!/usr/bin/env bash
# Issue 13's acceptance: every test file passes when run alone (no test depends on another file having
# run first). Prints one line per file: passed/skipped counts, or FAIL. Usage: bash tools/each_test_file_alone.sh
set -u
cd "$(dirname "$0")/.."
status=0
for f in tests/test_*.py; do
    out=$(python -m pytest -q -p no:cacheprovider -p no:randomly -rs "$f" 2>&1 | tail -n 30)
    last=$(printf '%s\n' "$out" | grep -E "passed|failed|error" | tail -n 1)
    skips=$(printf '%s\n' "$out" | grep -c "^SKIPPED" || true)
    case "$last" in
        *failed*|*error*) echo "FAIL  $f: $last"; status=1 ;;
        *) echo "ok    $f: $last (skip lines: $skips)" ;;
    esac
done
exit $status
