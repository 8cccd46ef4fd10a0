#!/bin/sh
# The test groups' logs (build/test-logs/GROUP.log, one per group, written by
# make's parallel jobs) added up: each failing case and its checks, the log's
# tail of a group that ended without its summary line (a crash, a sanitizer
# report), one line per group, and "N passed, N failed" last. Exits 1 when
# anything failed, a group did not finish or fewer than EXPECTED groups left
# a log: tests/summary.sh DIR [EXPECTED].
dir=${1:-build/test-logs}
expected=${2:-0}
status=0 passed=0 failed=0 left=0 groups=0
for log in "$dir"/*.log; do
    [ -e "$log" ] || { echo "no test logs in $dir"; exit 2; }
    group=$(basename "$log" .log)
    groups=$((groups + 1))
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed' "$log" | tail -n 1)
    if [ -z "$line" ]; then
        echo "== $group did not finish; the end of $log:"
        tail -n 30 "$log"
        status=1
        continue
    fi
    set -- $line
    p=$1 f=$3
    l=$(echo "$line" | sed -n 's/.*(\([0-9]*\) left to make check.*/\1/p')
    passed=$((passed + p)) failed=$((failed + f)) left=$((left + ${l:-0}))
    if [ "$f" -gt 0 ]; then
        echo "== $group: $f failed ($log):"
        grep -E '^(FAIL|    )' "$log"
        status=1
    fi
    grep -E '^--   ' "$log"
    secs=$(sed -n 's/^group .* ran \([0-9]*\) s$/\1/p' "$log")
    printf '%-16s %-28s %5s s\n' "$group" "$line" "$secs"
done
# a group whose job never ran (make stopped) has no log at all
if [ "$groups" -lt "$expected" ]; then
    echo "only $groups of $expected test groups left a log in $dir"
    status=1
fi
if [ "$left" -gt 0 ]; then
    echo "$passed passed, $failed failed ($left left to make check: they need programs besides gcc)"
else
    echo "$passed passed, $failed failed"
fi
exit $status
