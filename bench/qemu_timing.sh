#!/bin/sh
# make bench: the Cortex-M3 image's step timing under QEMU -icount, for a
# short print with masks streaming (the hand at --scale 5, planned by the
# printer, 21 layers): the trace image (build/fw-mps2-trace.elf,
# -DCM3_TRACE) reports the worst lateness of a step's alarm interrupt after
# its scheduled tick and the worst loop pass (idle left out; the loop's own
# work, its interrupts' cycles out, and with them in: QEMU's UART moves a
# reply's bytes at once, so their interrupts bunch up in one pass), in
# cycles of the an385's 25 MHz clock. tests/test_qemu_timing.c asserts the
# own work under a step interval; here it is only reported.
#   bench/qemu_timing.sh ELF TOOL
set -e
repo=$(pwd)
elf=$(realpath "$1")
tool=$(realpath "$2")
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cd "$dir"
timeout 300 qemu-system-arm -M mps2-an385 -nographic -monitor none -serial pty \
    -semihosting-config enable=on,target=native -icount shift=5,align=off,sleep=off -kernel "$elf" \
    > qemu.out 2> qemu.err &
qemu=$!
port=
for i in $(seq 100); do
    port=$(grep -o '/dev/pts/[0-9]*' qemu.out || true)
    [ -n "$port" ] && break
    sleep 0.1
done
if ! "$tool" print "$repo/examples/models/hand_closed.obj" --scale 5 --port "$port" --exposure 0.05 --penetration 0.1 \
        --bottom-layers 1 --bottom-exposure 0.1 --peel 0.5 --peel-speed 10 --return-speed 10 --settle 0.02 \
        --then-exit > print.out 2>&1; then
    cat print.out qemu.err
    kill "$qemu"
    exit 1
fi
wait "$qemu"
awk -F' ' '
    /trace steps/ { steps = $NF }
    /worst step lateness/ { late = $NF }
    /worst loop pass \(cycles\)/ { pass = $NF }
    /worst loop pass while Z moves/ { moving = $NF }
    /own work, worst pass \(cycles\)/ { work = $NF }
    /own work, worst pass while Z moves/ { moving_work = $NF }
    END {
        if (steps == "") { print "qemu timing: no summary from the image"; exit 1 }
        printf "QEMU -icount, mps2 (25 MHz), a print with masks streaming: %d steps, worst step lateness %d cycles (%.1f us); worst loop pass, the loop'"'"'s own work, %d cycles (%.2f ms), %d while Z moves (%.2f ms), the step interval at 10 mm/s 6250; with the interrupts that came in them %d and %d\n", \
            steps, late, late / 25, work, work / 25000, moving_work, moving_work / 25000, pass, moving
    }' qemu.err
