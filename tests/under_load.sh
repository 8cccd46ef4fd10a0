#!/bin/sh
# One test case run again and again beside two busy processes (a shared
# 2-core CI machine): tests/under_load.sh [RUNS [CASE [GROUP]]], from the
# repository's root with build/san/run_tests, build/san/adaslice and what
# the case needs built. Prints each run's result and time, then
# "passed P of N"; exits 0 only when every run passed.
runs=${1:-20}
case_name=${2:-gcode_print_by_printcore}
group=${3:-avr}
log=build/under_load
mkdir -p "$log" || exit 2
# a copy, so that a rebuild meanwhile changes nothing
cp build/san/run_tests "$log/run_tests" || exit 2
if command -v stress-ng >/dev/null 2>&1; then
    stress-ng --cpu 2 --quiet & busy="$!"
else
    sh -c 'while :; do :; done' & busy="$!"
    sh -c 'while :; do :; done' & busy="$busy $!"
fi
trap 'kill $busy 2>/dev/null' EXIT
trap 'exit 1' INT TERM
passed=0
i=1
while [ "$i" -le "$runs" ]; do
    start=$(date +%s)
    if ADASLICE_BIN=build/san/adaslice "$log/run_tests" --case "$case_name" "$group" >"$log/run$i.txt" 2>&1; then
        passed=$((passed + 1)); result=ok
    else
        result=FAIL
    fi
    echo "run $i: $result in $(($(date +%s) - start)) s (load $(cut -d' ' -f1 /proc/loadavg))"
    [ "$result" = ok ] || sed -n '/^    /p' "$log/run$i.txt" | head -5
    i=$((i + 1))
done
echo "passed $passed of $runs: $case_name under two busy processes"
[ "$passed" -eq "$runs" ]
