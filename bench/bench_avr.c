/* make bench: the RAMPS 1.4 / ATmega2560 firmware under simavr, cycle-exact.

       bench_avr AVR-RUN AVR-BENCH.ELF FW-RAMPS-TEST.ELF FW-RAMPS.ELF ADASLICE [avr-size]

   1. bench/avr_bench.c's image under avr-run: one step of motion.c's closed
      form (fw_axis_step) in cycles, at 10 mm/s and at the board's top speed,
      on the ramps and cruising; a halt; homing; and the planner
      (adaslice_dp) over BOARD_MAX_BINS bins: cycles per bin.
   2. A binary-protocol print with masks streaming while Z moves (adaslice
      print of the bundled hand at scale 5 on the 240 x 200 test display):
      from avr-run's pin log, the worst step's distance from the tick the
      closed form gives it (each move replayed by the real motion.c from its
      first step), steps refused as late, and the worst loop pass (all, and
      while Z moves; its interrupts in, and the loop's own work), the
      stack's peak.
   3. The shipped image (its 2560 x 1440 display: 320-byte rows, each row's
      CRC over several passes) printing the hand at scale 2, 9 layers: the
      worst loop pass, all and while Z moves, the whole command's wall time
      and the longest wait for a reply (a whole mask decoding), and the
      frames the host sent again (resends while a mask decodes are waste).
   4. SRAM: the shipped image's data + bss (avr-size), the planner's share,
      and the largest BOARD_MAX_BINS that still leaves the stack its
      reserve (stack.ld: the link refuses more) and the stack's canary. */
#define _XOPEN_SOURCE 700
#include "../firmware/motion.h"
#include "../firmware/ports/ramps/board.h"
#include "../link/tty.h"
#include "../tests/avr_passes.h"
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static const char *arg_run, *arg_bench, *arg_test, *arg_ship, *arg_tool, *arg_size = "avr-size";

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec / 1e9;
}

/* avr-run IMAGE with `log` (or none); its pty name in `pty`; the child's pid. */
static pid_t start(const char *image, const char *log, const char *z, char *pty, size_t size)
{
    int fds[2];
    pid_t pid;
    char line[256];
    size_t len = 0;
    double t0 = now_s();
    if (pipe(fds) != 0) return -1;
    fflush(NULL);
    pid = fork();
    if (pid == 0) {
        dup2(fds[1], 1);
        close(fds[0]);
        if (log) execl(arg_run, arg_run, "--log", log, "--z-start", z, "--timeout", "300", image, (char *)NULL);
        else execl(arg_run, arg_run, "--timeout", "300", image, (char *)NULL);
        _exit(127);
    }
    close(fds[1]);
    while (now_s() - t0 < 10) {
        struct pollfd p = {fds[0], POLLIN, 0};
        char ch;
        if (poll(&p, 1, 100) <= 0) continue;
        if (read(fds[0], &ch, 1) != 1) break;
        if (ch != '\n') { if (len + 1 < sizeof line) line[len++] = ch; continue; }
        line[len] = 0;
        len = 0;
        if (!strncmp(line, "pty ", 4)) { snprintf(pty, size, "%s", line + 4); close(fds[0]); return pid; }
    }
    close(fds[0]);
    return pid;
}

static void stop(pid_t pid)
{
    int st;
    if (pid <= 0) return;
    kill(pid, SIGTERM);
    waitpid(pid, &st, 0);
}

static unsigned long long field(const char *text, const char *name)
{
    char key[64];
    const char *p;
    snprintf(key, sizeof key, " %s=", name);
    p = strstr(text, key);
    return p ? strtoull(p + strlen(key), NULL, 10) : 0;
}

static void board_axis(fw_axis *axis)
{
    fw_axis_config c;
    c.steps_per_mm = BOARD_STEPS_PER_MM;
    c.max_speed = BOARD_MAX_STEPS_S;
    c.accel = BOARD_ACCEL_STEPS_S2;
    c.home_speed = BOARD_HOME_STEPS_S;
    c.max_steps = (int32_t)BOARD_Z_MAX_STEPS;
    c.home_travel = (int32_t)BOARD_HOME_TRAVEL_STEPS;
    fw_axis_init(axis, &c, BOARD_CLOCK_HZ);
}

/* adaslice print of the bundled hand at `scale` on IMAGE under avr-run
   (pin log `log`, Z starting `z` mm up; a --report when `report`), the
   whole command's wall time in *wall. 0, or 1 after saying what failed. */
static int print_hand(const char *image, const char *log, const char *z, const char *scale, const char *report, double *wall)
{
    char pty[256], cmd[1024];
    pid_t pid = start(image, log, z, pty, sizeof pty);
    double t0;
    int status;
    if (pid <= 0 || !pty[0]) { printf("bench_avr: FAILED: avr-run did not start %s\n", image); stop(pid); return 1; }
    snprintf(cmd, sizeof cmd,
             "%s print examples/models/hand_closed.obj --scale %s --port %s --exposure 0.05 --penetration 0.1 --bottom-layers 1 "
             "--bottom-exposure 0.1 --peel 3 --peel-speed 10 --return-speed 10 --settle 0.02%s%s > /dev/null 2>&1",
             arg_tool, scale, pty, report ? " --report " : "", report ? report : "");
    t0 = now_s();
    status = system(cmd);
    *wall = now_s() - t0;
    stop(pid);
    if (status != 0) { printf("bench_avr: FAILED: the print did not complete (%s)\n", cmd); return 1; }
    return 0;
}

int main(int argc, char **argv)
{
    char pty[256], text[2048], cmd[1024];
    size_t n = 0;
    pid_t pid;
    int fd;
    double t0;
    if (argc < 6) { fprintf(stderr, "usage: bench_avr AVR-RUN AVR-BENCH.ELF FW-RAMPS-TEST.ELF FW-RAMPS.ELF ADASLICE [avr-size]\n"); return 2; }
    arg_run = argv[1]; arg_bench = argv[2]; arg_test = argv[3]; arg_ship = argv[4]; arg_tool = argv[5];
    if (argc > 6) arg_size = argv[6];

    /* 1. the arithmetic */
    pid = start(arg_bench, NULL, "0", pty, sizeof pty);
    fd = pid > 0 ? open(pty, O_RDWR | O_NOCTTY | O_NONBLOCK) : -1;
    if (fd < 0 || tty_raw(fd, 0) != 0) { printf("bench_avr: FAILED: avr-run did not start %s\n", arg_bench); stop(pid); return 1; }
    t0 = now_s();
    text[0] = 0;
    while (now_s() - t0 < 120 && !strstr(text, " END")) {
        struct pollfd p = {fd, POLLIN, 0};
        ssize_t got;
        if (poll(&p, 1, 100) <= 0) continue;
        got = read(fd, text + n, sizeof text - 1 - n);
        if (got > 0) { n += (size_t)got; text[n] = 0; }
    }
    close(fd);
    stop(pid);
    if (!strstr(text, "AVRBENCH") || !strstr(text, " END")) { printf("bench_avr: FAILED: no result line from %s\n", arg_bench); return 1; }
    printf("ATmega2560 at 16 MHz under simavr (cycle-exact), motion.c's fw_axis_step per step:\n");
    printf("  10 mm/s (a step every 4,000 cycles): ramp mean %llu, worst %llu; cruise mean %llu, worst %llu cycles\n",
           field(text, "ramp10_mean"), field(text, "ramp10_worst"), field(text, "cruise10_mean"), field(text, "cruise10_worst"));
    printf("  %.1f mm/s, the board's top (a step every %lu cycles): ramp mean %llu, worst %llu; cruise mean %llu, worst %llu cycles\n",
           BOARD_MAX_SPEED_UM_S / 1000.0, (unsigned long)(BOARD_CPU_HZ / BOARD_MAX_STEPS_S), field(text, "ramp_mean"),
           field(text, "ramp_worst"), field(text, "cruise_mean"), field(text, "cruise_worst"));
    printf("  a halt (brake and the next step): worst %llu cycles; homing: worst %llu cycles a step\n", field(text, "halt_worst"),
           field(text, "home_worst"));
    printf("a mask row's CRC-32, 2560 pixels (320 bytes): %llu cycles\n", field(text, "row_crc"));
    printf("the planner on the MCU, %llu bins (%llu bytes of workspace): init %llu, push %llu cycles/bin (%.1f ms for all), "
           "reverse %llu cycles; %llu layers\n",
           field(text, "bins"), field(text, "workspace"), field(text, "init"), field(text, "push") / (field(text, "bins") ? field(text, "bins") : 1),
           field(text, "push") / 16000.0, field(text, "reverse"), field(text, "layers"));

    /* 2. a print with masks streaming */
    {
        const char *log = "build/bench_avr_print.log";
        FILE *f;
        char line[256];
        uint64_t *at = NULL;
        int *dir = NULL;
        size_t steps = 0, cap = 0, i, from, late_worst = 0;
        uint64_t shortest = UINT64_MAX;
        long pos, start_steps = 0;
        avr_passes ps = {0, 0, 0, 0, 0, 0, 0, 0};
        double wall;
        if (print_hand(arg_test, log, "3", "5", NULL, &wall)) return 1;
        if (!(f = fopen(log, "r"))) { printf("bench_avr: FAILED: no log %s\n", log); return 1; }
        while (fgets(line, sizeof line, f)) {
            unsigned long long c;
            char what[16], a[16];
            const char *v;
            if (line[0] == '#') {
                if ((v = strstr(line, "start_steps="))) start_steps = strtol(v + 12, NULL, 10);
                avr_read_passes(line, &ps);
                continue;
            }
            if (sscanf(line, "%llu %15s %15s", &c, what, a) == 3 && !strcmp(what, "step")) {
                if (steps == cap) {
                    cap = cap ? 2 * cap : 65536;
                    at = (uint64_t *)realloc(at, cap * sizeof *at);
                    dir = (int *)realloc(dir, cap * sizeof *dir);
                    if (!at || !dir) return 1;
                }
                at[steps] = c;
                dir[steps++] = a[0] == '-' ? -1 : 1;
            }
        }
        fclose(f);
        /* homing ends at the last step that leaves Z at the switch; then the
           moves, split where the direction turns or the axis rested */
        for (pos = start_steps, from = 0, i = 0; i < steps; i++) { pos += dir[i]; if (pos == 0) from = i + 1; }
        for (pos = 0, i = from; i < steps;) {
            size_t j = i + 1, k;
            fw_axis axis;
            while (j < steps && dir[j] == dir[i] && at[j] - at[j - 1] < 2u * 8u * 20000u) j++;
            board_axis(&axis);
            axis.homed = 1;
            axis.position = (int32_t)pos;
            (void)fw_axis_move_to(&axis, (int32_t)(pos + dir[i] * (long)(j - i)), 0, 0);
            for (k = i; k < j && fw_axis_busy(&axis); k++) {
                uint64_t want = fw_axis_next(&axis) * BOARD_TICK_DIV, got = at[k] - at[i];
                size_t off = (size_t)(want > got ? want - got : got - want);
                (void)fw_axis_step(&axis, 0);
                if (off > late_worst) late_worst = off;
            }
            for (k = i + 1; k < j; k++)
                if (at[k] - at[k - 1] < shortest) shortest = at[k] - at[k - 1];
            pos += dir[i] * (long)(j - i);
            i = j;
        }
        printf("a binary print with masks streaming (%zu steps): worst step %zu cycles (%.2f us) from its closed-form tick, "
               "%lu refused as late\n", steps, late_worst, late_worst / 16.0, ps.late);
        {
            /* the step queue less a refill at the top speed: what a pass begins with */
            unsigned gap = FW_STEP_FILL < FW_STEP_QUEUE / 2u ? FW_STEP_FILL : FW_STEP_QUEUE / 2u;
            unsigned long cover = (unsigned long)(FW_STEP_QUEUE - gap) * (BOARD_CPU_HZ / BOARD_MAX_STEPS_S);
            printf("  Z's top speed from the pin edges: %.2f mm/s (the shortest interval %llu cycles; BOARD_MAX_SPEED_UM_S %lu), "
                   "peels of 3 mm at 10 mm/s\n",
                   shortest < UINT64_MAX ? (double)BOARD_CPU_HZ / (double)shortest / BOARD_STEPS_PER_MM : 0.0,
                   (unsigned long long)(shortest < UINT64_MAX ? shortest : 0), (unsigned long)BOARD_MAX_SPEED_UM_S);
            printf("  worst loop pass %lu cycles, %lu while Z moves (its interrupts in; the loop's own work %lu, %lu); the "
                   "step queue less a refill (%u steps) covers %lu cycles at the top speed: %.0f %% of it to spare; stack peak %lu bytes\n",
                   ps.worst, ps.moving, ps.work, ps.moving_work, (unsigned)(FW_STEP_QUEUE - gap), cover,
                   100.0 * (1.0 - (double)ps.worst / (double)cover), ps.stack);
        }
        free(at);
        free(dir);

        /* 3. the shipped image, 2560 x 1440 */
        {
            const char *ship_log = "build/bench_avr_ship.log", *report = "build/bench_avr_ship.json";
            avr_passes sp = {0, 0, 0, 0, 0, 0, 0, 0};
            double longest = -1;
            long resent = -1;
            char *j, json[65536];
            size_t got;
            if (print_hand(arg_ship, ship_log, "1", "2", report, &wall)) return 1;
            if (!(f = fopen(ship_log, "r"))) { printf("bench_avr: FAILED: no log %s\n", ship_log); return 1; }
            while (fgets(line, sizeof line, f))
                if (line[0] == '#') avr_read_passes(line, &sp);
            fclose(f);
            if ((f = fopen(report, "r"))) {
                got = fread(json, 1, sizeof json - 1, f);
                json[got] = 0;
                fclose(f);
                if ((j = strstr(json, "\"longest_wait_ms\": "))) longest = strtod(j + 19, NULL);
                if ((j = strstr(json, "\"retransmitted_frames\": "))) resent = strtol(j + 24, NULL, 10);
            }
            printf("the shipped image (2560 x 1440, rows of 320 bytes, FW_CRC_BYTES %u of CRC a pass), 9 layers of the hand at "
                   "scale 2: worst loop pass %lu cycles, %lu while Z moves (the loop's own work %lu, %lu); %lu steps refused "
                   "as late; the whole print %.1f s of the wall, the longest wait for a reply %.2f s (a whole mask decoding), "
                   "%ld frames sent again\n",
                   (unsigned)FW_CRC_BYTES, sp.worst, sp.moving, sp.work, sp.moving_work, sp.late, wall, longest / 1000, resent);
        }

        /* 4. SRAM */
        {
            FILE *p;
            unsigned long text_b = 0, data = 0, bss = 0;
            snprintf(cmd, sizeof cmd, "%s %s", arg_size, arg_ship);
            if ((p = popen(cmd, "r"))) {
                if (fgets(line, sizeof line, p) && fgets(line, sizeof line, p)) sscanf(line, "%lu %lu %lu", &text_b, &data, &bss);
                pclose(p);
            }
            if (data + bss) {
                long left = 8192L - (long)(data + bss) - 2L - (long)ps.reserve;
                printf("SRAM (%s): %lu bytes data + bss of 8192, the planner %lu of them (BOARD_MAX_BINS %u: 3,072 of rings "
                       "+ a byte a bin), %lu reserved for the stack (its peak measured %lu), %ld free beyond the reserve and "
                       "the canary: the largest BOARD_MAX_BINS that links is %ld\n",
                       arg_ship, data + bss, (unsigned long)(128u * 24u + BOARD_MAX_BINS + 1u), BOARD_MAX_BINS, ps.reserve,
                       ps.stack, left, (long)BOARD_MAX_BINS + left);
            }
        }
    }
    return 0;
}
