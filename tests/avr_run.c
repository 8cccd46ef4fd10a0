/* avr-run: an ATmega2560 firmware image (build/fw-ramps*.elf) under simavr,
   cycle-exact, as the RAMPS printer it drives. It prints "pty /dev/pts/N",
   serves that terminal as the Mega's USB serial port (UART0), models the Z
   carriage from the STEP and DIR pins and drives the Z-min endstop from it,
   and writes every pin edge to a log with its CPU cycle, in fw-sim's format
   where the events are the same (tests/test_print.c's reader takes both):

       # avr-run tick_hz=16000000 steps_per_mm=400 max_speed=4000 accel=20000 start_steps=12000 ...
       <cycle> step +1 | step -1     STEP rises (DIR as it is then)
       <cycle> step_end              STEP falls
       <cycle> dir 1 | dir 0         DIR (1 = up)
       <cycle> motor 1 | motor 0     the driver enabled (Z_ENABLE low)
       <cycle> uv 1 | uv 0           the D8 MOSFET
       <cycle> show <slot> 0 0       the core shows a display buffer (GPIOR1; there is
       <cycle> show -1               no display on this board, so no CRC: 0)
       <cycle> reset                 the MCU reset (the watchdog): every pin an input
       <cycle> late                  the firmware could not arm a step in time (STEP_LATE)
       <cycle> rx_eol                a line end from the host entered the UART (at most
                                     RX_AHEAD bytes ahead of the firmware reading them)
       <cycle> obstacle              SIGUSR1 put the obstacle of --obstacle-at in place
       <cycle> pass <cycles>         a loop pass of at least --log-passes cycles (with
                                     --profile-passes: ": function cycles ..." after it)
       <cycle> canary                the stack's canary (stack.ld's __stack_canary) changed
       <cycle> screen <n> 0 <crc32> <lit>  --watch-screen: at the nth UV-on, the host's
                                     screen file (its CRC-32 and nonzero bytes; a copy in
                                     FILE.uv<n>); the layer is the firmware's, unseen here: 0
       <cycle> screen lit            --watch-screen: a STEP edge while the file held a
                                     nonzero byte (every edge is checked)
       # end cycles=C worst_pass=P worst_moving_pass=M worst_work=W worst_moving_work=V passes=N stack_peak=S
             stack_reserve=Q canary=K resets=R late=L

   worst_pass: the longest main-loop pass in cycles, from the firmware's
   GPIOR0 marks (a pass begins, the loop goes to sleep), the interrupts
   taken meanwhile included; worst_moving_pass the longest of those that
   began while Z moved; worst_work and worst_moving_work the same with the
   interrupts' cycles (from a vector's entry to its RETI) taken out: the
   loop's own work. simavr's UART runs at the line's rate, so the first two
   are what the part would see. stack_peak: bytes below the end of SRAM the
   stack reached, from SRAM painted before the run: the lowest byte no
   longer paint from the stack's room up (stack.ld's __stack_low, above
   the canary; a frame's buffer left unwritten is then a hole inside the
   stack, not its end); stack_reserve the room the link reserved for it
   (__stack_reserve), canary 1 if the canary changed after the first loop
   pass (the firmware writes it before).

   The UART: simavr's own uart_pty part raced and corrupted bulk data (team
   notes), so bytes from the pty are handed to the UART here, in the
   simulator's thread, only while the UART signals room (XON). Idle sleep is
   skipped, so virtual time runs as fast as the host allows, or at most
   --speed times the wall clock.

   Exit: 0 on SIGTERM/SIGINT, 4 when --max-seconds of virtual time or
   --timeout seconds of wall time pass first (said on stderr), 3 when the
   image crashes, 2 on a bad command line. */
#define _XOPEN_SOURCE 700 /* posix_openpt, grantpt, unlockpt, ptsname */
#include "../firmware/ports/ramps/board.h"
#include "../link/tty.h"
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_io.h>
#include <simavr/sim_core.h>
#include <simavr/sim_interrupts.h>
#include <simavr/sim_cycle_timers.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <gelf.h>

#define RAMSTART 0x200u
#define RAMEND   0x21FFu
#define PAINT    0xAAu
#define GPIOR0_ADDR 0x3Eu
#define GPIOR1_ADDR 0x4Au
#define GPIOR2_ADDR 0x4Bu
#define PIND_ADDR   0x29u
#define UCSR0B_ADDR 0xC1u
#define UCSR0B_RXEN 0x10u
#define POLL_CYCLES 1000u /* between looks at the pty: < a byte at 115200 baud (1389 cycles) */
/* USART0 RX's vector (ATmega2560 datasheet table 14-1: program address
   $0032, in words): its interrupt taken is a byte the firmware got */
#define RX_VECTOR 0x64u
/* bytes handed to simavr's UART ahead of the firmware's reading them: its
   input FIFO holds 64, which would hold a line end back 5 ms from the
   part; two keep the line busy, as the real USART's buffer does */
#define RX_AHEAD 2u

static const char USAGE[] =
    "usage: avr-run [options] IMAGE.elf\n"
    "Runs an ATmega2560 image under simavr as a RAMPS printer; prints \"pty PATH\" and serves it.\n"
    "  --log FILE         pin edges with their cycle                   [none]\n"
    "  --z-start MM       carriage height above the endstop at start  [30]\n"
    "  --speed S          at most S times real time (0: unpaced)      [0]\n"
    "  --max-seconds S    virtual time budget                          [600]\n"
    "  --timeout S        wall-clock budget                            [300]\n"
    "  --log-passes C     log the loop passes of C cycles or more      [none]\n"
    "  --profile-passes C the same with the functions they spent their cycles in [none]\n"
    "  --hang-at-uv N     make the main loop hang when UV goes on the Nth time\n"
    "                     (a RAMPS_TEST_HANG image: the watchdog test)  [never]\n"
    "  --obstacle-at MM   once SIGUSR1 arrives, the endstop also reads pressed\n"
    "                     while the carriage is at or below MM (a crash)  [none]\n"
    "  --overrun-at-uv N  make the stack overrun its room down to the canary when UV\n"
    "                     goes on the Nth time (a RAMPS_TEST_OVERRUN image) [never]\n"
    "  --watch-screen F   the host's screen file (adaslice print --screen file:F,...), read\n"
    "                     at every UV-on and STEP edge, as fw-sim's        [none]\n";

static volatile sig_atomic_t stop_signal, obstacle_signal;
static void on_signal(int sig) { stop_signal = sig; }
static void on_usr1(int sig) { (void)sig; obstacle_signal = 1; }

typedef struct run {
    avr_t *avr;
    FILE *log;
    int master;
    int32_t position;            /* carriage, steps above the switching point */
    int32_t obstacle;            /* steps: pressed at or below this too, once placed */
    int obstacle_placed;
    int step, dir, en, uv, endstop;
    avr_irq_t *endstop_irq, *uart_in;
    int xon;
    uint8_t in[4096];
    size_t in_len, in_at;
    uint8_t *out;
    size_t out_len, out_cap;
    uint64_t pass_begin, worst_pass, worst_moving, passes, log_passes;
    uint64_t isr_cycles, pass_isr, worst_work, worst_moving_work; /* cycles in interrupt handlers */
    int pass_moving, in_isr;
    unsigned long resets, late, uv_ons, poke_at_uv;
    uint8_t poke;                /* what GPIOR2 gets at the poke_at_uv'th UV on */
    unsigned stack_low, canary_addr; /* SRAM addresses from the image's symbols */
    unsigned long stack_reserve;
    uint8_t canary[2];
    int canary_state;            /* 0 not yet written, 1 watched, 2 changed */
    int in_pass;
    uint64_t slept;              /* cycles the core spent asleep */
    unsigned long rx_pushed, rx_taken; /* bytes into simavr's UART, RX interrupts taken */
    const char *watch;           /* --watch-screen */
    unsigned long lit_steps;
} run;

static run R;

/* --profile-passes: each instruction's cycles go to the function its PC is
   in (the image's symbol table), summed over a pass; a pass of at least C
   cycles is logged with the functions that took most of it. */
#define PROFILE_TOP 10
typedef struct func { uint32_t addr, size; char name[48]; } func;
static struct { func *f; size_t n; uint16_t *at; uint64_t *cycles, threshold; } P;

static int by_addr(const void *a, const void *b)
{
    const func *x = (const func *)a, *y = (const func *)b;
    return x->addr < y->addr ? -1 : x->addr > y->addr;
}

/* Functions (sized) and the global labels of assembly routines (libgcc's,
   unsized: up to the next symbol) of the image's code. */
static int load_functions(const char *path)
{
    int fd = open(path, O_RDONLY);
    Elf *e;
    Elf_Scn *scn = NULL;
    size_t i, cap = 0, words = 0;
    if (fd < 0 || elf_version(EV_CURRENT) == EV_NONE || !(e = elf_begin(fd, ELF_C_READ, NULL))) return 0;
    while ((scn = elf_nextscn(e, scn)) != NULL) {
        GElf_Shdr sh;
        Elf_Data *d;
        if (!gelf_getshdr(scn, &sh) || sh.sh_type != SHT_SYMTAB || !(d = elf_getdata(scn, NULL))) continue;
        for (i = 0; i < sh.sh_size / sh.sh_entsize; i++) {
            GElf_Sym sym;
            GElf_Shdr in;
            const char *name;
            int type;
            if (!gelf_getsym(d, (int)i, &sym) || !(name = elf_strptr(e, sh.sh_link, sym.st_name)) || !name[0]) continue;
            type = GELF_ST_TYPE(sym.st_info);
            if (sym.st_shndx == SHN_UNDEF || sym.st_shndx >= SHN_LORESERVE ||
                !gelf_getshdr(elf_getscn(e, sym.st_shndx), &in) || !(in.sh_flags & SHF_EXECINSTR))
                continue;
            if (!(type == STT_FUNC && sym.st_size) && !(type == STT_NOTYPE && GELF_ST_BIND(sym.st_info) == STB_GLOBAL)) continue;
            if (P.n == cap) {
                cap = cap ? 2 * cap : 256;
                if (!(P.f = (func *)realloc(P.f, (cap + 1) * sizeof *P.f))) return 0;
            }
            P.f[P.n].addr = (uint32_t)sym.st_value;
            P.f[P.n].size = (uint32_t)sym.st_size;
            snprintf(P.f[P.n].name, sizeof P.f[P.n].name, "%s", name);
            if ((sym.st_value + sym.st_size) / 2 + 1 > words) words = (sym.st_value + sym.st_size) / 2 + 1;
            P.n++;
        }
    }
    elf_end(e);
    close(fd);
    if (!P.n || P.n >= 0xFFFF) return 0;
    qsort(P.f, P.n, sizeof *P.f, by_addr);
    snprintf(P.f[P.n].name, sizeof P.f[P.n].name, "(other)");
    words += 64; /* an unsized routine at the end */
    P.at = (uint16_t *)malloc(words * sizeof *P.at);
    P.cycles = (uint64_t *)calloc(P.n + 1, sizeof *P.cycles);
    if (!P.at || !P.cycles) return 0;
    for (i = 0; i < words; i++) P.at[i] = (uint16_t)P.n;
    /* each symbol up to the next, then the sized functions over them */
    for (i = 0; i < P.n; i++) {
        uint32_t w, end = i + 1 < P.n ? P.f[i + 1].addr / 2 : (uint32_t)words;
        for (w = P.f[i].addr / 2; w < end && w < words; w++) P.at[w] = (uint16_t)i;
    }
    for (i = 0; i < P.n; i++) {
        uint32_t w;
        for (w = P.f[i].addr / 2; w < (P.f[i].addr + P.f[i].size) / 2; w++) P.at[w] = (uint16_t)i;
    }
    P.f[P.n].addr = (uint32_t)words; /* the table's end */
    return 1;
}

/* The values of the named symbols of the image (0 for one it lacks); 0 if
   the image has no symbol table. */
static int read_symbols(const char *path, const char *const *names, unsigned long *values, size_t count)
{
    int fd = open(path, O_RDONLY), found = 0;
    Elf *e;
    Elf_Scn *scn = NULL;
    size_t i, k;
    for (k = 0; k < count; k++) values[k] = 0;
    if (fd < 0) return 0;
    if (elf_version(EV_CURRENT) == EV_NONE || !(e = elf_begin(fd, ELF_C_READ, NULL))) { close(fd); return 0; }
    while ((scn = elf_nextscn(e, scn)) != NULL) {
        GElf_Shdr sh;
        Elf_Data *d;
        if (!gelf_getshdr(scn, &sh) || sh.sh_type != SHT_SYMTAB || !(d = elf_getdata(scn, NULL))) continue;
        found = 1;
        for (i = 0; i < sh.sh_size / sh.sh_entsize; i++) {
            GElf_Sym sym;
            const char *name;
            if (!gelf_getsym(d, (int)i, &sym) || !(name = elf_strptr(e, sh.sh_link, sym.st_name))) continue;
            for (k = 0; k < count; k++)
                if (!strcmp(name, names[k])) values[k] = (unsigned long)sym.st_value;
        }
    }
    elf_end(e);
    close(fd);
    return found;
}

static void profile_pass(uint64_t begin, uint64_t took)
{
    size_t i, k;
    if (took >= P.threshold && R.log) {
        fprintf(R.log, "%llu pass %llu%s:", (unsigned long long)begin, (unsigned long long)took, R.pass_moving ? " moving" : "");
        for (k = 0; k < PROFILE_TOP; k++) {
            size_t best = P.n + 1;
            for (i = 0; i <= P.n; i++)
                if (P.cycles[i] && (best > P.n || P.cycles[i] > P.cycles[best])) best = i;
            if (best > P.n) break;
            fprintf(R.log, " %s %llu", P.f[best].name, (unsigned long long)P.cycles[best]);
            P.cycles[best] = 0;
        }
        fputc('\n', R.log);
    }
    memset(P.cycles, 0, (P.n + 1) * sizeof *P.cycles);
}

static void log_event(const char *event)
{
    if (R.log) fprintf(R.log, "%llu %s\n", (unsigned long long)R.avr->cycle, event);
}

/* The switch's level on PD3, raised again whenever the pin reads otherwise
   (the firmware's pull-up write makes simavr read the pin high). */
static void drive_endstop(void)
{
    int pressed = R.position <= 0 || (R.obstacle_placed && R.position <= R.obstacle);
    if (pressed != R.endstop || ((R.avr->data[PIND_ADDR] >> 3) & 1) != pressed) {
        R.endstop = pressed;
        avr_raise_irq(R.endstop_irq, (uint32_t)pressed); /* NC switch: high = pressed */
    }
}

/* --watch-screen: the file's bytes now (malloc'd), NULL if unreadable. */
static unsigned char *screen_bytes(size_t *size)
{
    FILE *f = fopen(R.watch, "rb");
    unsigned char *b = NULL;
    long n;
    *size = 0;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (b = (unsigned char *)malloc((size_t)n)) != NULL && fread(b, 1, (size_t)n, f) == (size_t)n)
        *size = (size_t)n;
    fclose(f);
    return b;
}

static void watch_step(void)
{
    size_t n, k;
    unsigned char *b;
    if (!R.watch) return;
    b = screen_bytes(&n);
    for (k = 0; k < n && !b[k]; k++) {}
    if (k < n && R.lit_steps++ < 1000) log_event("screen lit");
    free(b);
}

static void watch_uv_on(void)
{
    size_t n, k, lit = 0;
    unsigned char *b;
    uint32_t crc = 0xffffffffu;
    char copy[512];
    FILE *f;
    if (!R.watch || !R.log) return;
    b = screen_bytes(&n);
    for (k = 0; k < n; k++) {
        int bit;
        lit += b[k] != 0;
        crc ^= b[k];
        for (bit = 0; bit < 8; bit++) crc = crc >> 1 ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    fprintf(R.log, "%llu screen %lu 0 %08lx %zu\n", (unsigned long long)R.avr->cycle, R.uv_ons,
            (unsigned long)(crc ^ 0xffffffffu), lit);
    snprintf(copy, sizeof copy, "%s.uv%lu", R.watch, R.uv_ons);
    if (b && (f = fopen(copy, "wb")) != NULL) {
        (void)fwrite(b, 1, n, f);
        fclose(f);
    }
    free(b);
}

static void on_step(struct avr_irq_t *irq, uint32_t value, void *param)
{
    int v = value != 0;
    (void)irq;
    (void)param;
    if (v == R.step) return;
    R.step = v;
    if (v) {
        R.position += R.dir ? 1 : -1;
        watch_step();
        log_event(R.dir ? "step +1" : "step -1");
        drive_endstop();
    } else {
        log_event("step_end");
    }
}

static void on_dir(struct avr_irq_t *irq, uint32_t value, void *param)
{
    int v = value != 0;
    (void)irq;
    (void)param;
    if (v == R.dir) return;
    R.dir = v;
    log_event(v ? "dir 1" : "dir 0");
}

static void on_enable(struct avr_irq_t *irq, uint32_t value, void *param)
{
    int on = value == 0; /* active low */
    (void)irq;
    (void)param;
    if (on == R.en) return;
    R.en = on;
    log_event(on ? "motor 1" : "motor 0");
}

static void on_uv(struct avr_irq_t *irq, uint32_t value, void *param)
{
    int v = value != 0;
    (void)irq;
    (void)param;
    if (v == R.uv) return;
    R.uv = v;
    log_event(v ? "uv 1" : "uv 0");
    if (v && ++R.uv_ons == R.poke_at_uv) R.avr->data[GPIOR2_ADDR] = R.poke; /* the RAMPS_TEST_ hooks */
    if (v) watch_uv_on();
}

/* A loop pass from R.pass_begin to `end`: the worst, with and without its
   interrupts, and logged when it takes at least --log-passes cycles. */
static void end_pass(uint64_t end)
{
    uint64_t took = end - R.pass_begin, work = took - (R.isr_cycles - R.pass_isr);
    if (took > R.worst_pass) R.worst_pass = took;
    if (R.pass_moving && took > R.worst_moving) R.worst_moving = took;
    if (work > R.worst_work) R.worst_work = work;
    if (R.pass_moving && work > R.worst_moving_work) R.worst_moving_work = work;
    if (P.cycles) profile_pass(R.pass_begin, took);
    else if (R.log_passes && took >= R.log_passes && R.log)
        fprintf(R.log, "%llu pass %llu\n", (unsigned long long)R.pass_begin, (unsigned long long)took);
}

/* The firmware's marks (board.h): loop passes, boot, late steps. */
static void on_gpior0(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    avr->data[addr] = v;
    if (v == BOARD_MARK_LOOP || v == BOARD_MARK_MOVING) {
        if (!R.canary_state && R.canary_addr) { /* written by the firmware's start */
            memcpy(R.canary, avr->data + R.canary_addr, sizeof R.canary);
            R.canary_state = 1;
        }
        if (R.in_pass) end_pass(avr->cycle);
        R.in_pass = 1;
        R.pass_moving = v == BOARD_MARK_MOVING;
        R.pass_begin = avr->cycle;
        R.pass_isr = R.isr_cycles;
        R.passes++;
    } else if (v == BOARD_MARK_IDLE) {
        if (R.in_pass) end_pass(avr->cycle);
        R.in_pass = 0;
    } else if (v == BOARD_MARK_LATE) {
        R.late++;
        log_event("late");
    } else if (v == BOARD_MARK_BOOT) {
        R.in_pass = 0;
        if (R.canary_state == 1) R.canary_state = 0; /* written again before the loop */
    }
}

static void on_gpior1(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    avr->data[addr] = v;
    if (v) {
        char line[32];
        snprintf(line, sizeof line, "show %d 0 0", v - 1);
        log_event(line);
    } else {
        log_event("show -1");
    }
}

/* A reset makes every pin an input: the drivers' and the MOSFET's inputs
   fall to their pull resistors (STEP, DIR, UV low; ENABLE high: off). */
static void on_reset(void)
{
    R.resets++;
    R.in_isr = 0;
    R.rx_pushed = R.rx_taken; /* what the UART held is gone with it */
    log_event("reset");
    if (R.uv) { R.uv = 0; log_event("uv 0"); }
    if (R.step) { R.step = 0; log_event("step_end"); }
    if (R.en) { R.en = 0; log_event("motor 0"); }
}

static void on_uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (R.out_len == R.out_cap) {
        size_t cap = R.out_cap ? 2 * R.out_cap : 4096;
        uint8_t *p = (uint8_t *)realloc(R.out, cap);
        if (!p) return;
        R.out = p;
        R.out_cap = cap;
    }
    R.out[R.out_len++] = (uint8_t)value;
}

static void on_xon(struct avr_irq_t *irq, uint32_t value, void *param) { (void)irq; (void)value; (void)param; R.xon = 1; }
static void on_xoff(struct avr_irq_t *irq, uint32_t value, void *param) { (void)irq; (void)value; (void)param; R.xon = 0; }

/* simavr 1.6's avr_callback_run_raw, with two changes: sleeping costs no
   wall time (the cycles slept are added at once), and an interrupt already
   pending when the core executes SLEEP wakes it at once, as on the part.
   1.6 first skips to the next timer event: with "sei; sleep" an interrupt
   that arrived during the cli section then waited for the next Timer5
   event (a step's compare was served 4 ms late). */
#define RETI 0x9518u

static void run_one(avr_t *avr)
{
    avr_flashaddr_t new_pc = avr->pc, pc = avr->pc;
    avr_cycle_count_t sleep;
    uint64_t c0 = avr->cycle, c1;
    int reti = R.in_isr && (unsigned)(avr->flash[pc] | avr->flash[pc + 1] << 8) == RETI;
    if (avr->state == cpu_Running) new_pc = avr_run_one(avr);
    sleep = avr_cycle_timer_process(avr);
    avr->pc = new_pc;
    if (avr->state == cpu_Sleeping) {
        if (!avr->sreg[S_I]) {
            avr->state = cpu_Done; /* asleep with interrupts off: nothing can wake it */
            return;
        }
        if (!avr_has_pending_interrupts(avr)) { avr->cycle += sleep; R.slept += sleep; }
        avr->cycle += 1;
    }
    c1 = avr->cycle;
    if (avr->state == cpu_Running || avr->state == cpu_Sleeping) avr_service_interrupts(avr);
    /* an interrupt handler's cycles, from its vector (the call's cycles
       included) to its RETI; the firmware's handlers do not nest */
    if (R.in_isr) {
        R.isr_cycles += c1 - c0;
        if (reti) R.in_isr = 0;
    }
    if (avr->pc != new_pc) {
        if (avr->pc == RX_VECTOR) R.rx_taken++;
        R.in_isr = 1;
        R.isr_cycles += avr->cycle - c1;
    }
    if (P.cycles && R.in_pass) P.cycles[pc / 2 < P.f[P.n].addr ? P.at[pc / 2] : P.n] += avr->cycle - c0;
    /* every instruction: two byte compares, not a call */
    if (R.canary_state == 1 && (avr->data[R.canary_addr] != R.canary[0] || avr->data[R.canary_addr + 1] != R.canary[1])) {
        R.canary_state = 2;
        log_event("canary");
    }
}

static double wall_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec / 1e9;
}

/* The pty: bytes to the host, bytes from it into the UART while it has room. */
static void serve_pty(void)
{
    if (R.out_len) {
        ssize_t n = write(R.master, R.out, R.out_len);
        if (n > 0) {
            memmove(R.out, R.out + n, R.out_len - (size_t)n);
            R.out_len -= (size_t)n;
        }
    }
    if (R.in_at == R.in_len) {
        ssize_t n = read(R.master, R.in, sizeof R.in);
        R.in_at = 0;
        R.in_len = n > 0 ? (size_t)n : 0;
    }
    /* only once the firmware has enabled the receiver (after each reset):
       simavr drops bytes a disabled UART gets */
    if (R.xon && (R.avr->data[UCSR0B_ADDR] & UCSR0B_RXEN) && R.in_at < R.in_len && R.rx_pushed - R.rx_taken < RX_AHEAD) {
        if (R.in[R.in_at] == '\n') log_event("rx_eol");
        R.rx_pushed++;
        avr_raise_irq(R.uart_in, R.in[R.in_at++]);
    }
}

static int open_pty(int *master, char *name, size_t size)
{
    const char *path;
    int slave;
    *master = posix_openpt(O_RDWR | O_NOCTTY);
    if (*master < 0 || grantpt(*master) || unlockpt(*master) || !(path = ptsname(*master)) || strlen(path) >= size) return -1;
    strcpy(name, path);
    if (fcntl(*master, F_SETFL, fcntl(*master, F_GETFL) | O_NONBLOCK) != 0) return -1;
    /* kept open so the master never sees a hangup while no host has it */
    slave = open(name, O_RDWR | O_NOCTTY);
    if (slave < 0 || tty_raw(slave, 0) != 0) return -1;
    return slave;
}

static unsigned long stack_peak(void)
{
    unsigned a = R.stack_low;
    while (a <= RAMEND && R.avr->data[a] == PAINT) a++;
    return RAMEND + 1u - a;
}

int main(int argc, char **argv)
{
    const char *elf = NULL, *log_path = NULL;
    double z_start = 30, speed = 0, max_seconds = 600, timeout = 300, t0, next_pace = 0;
    elf_firmware_t fw;
    char name[128];
    int i, slave, status = 0;
    uint64_t next_poll = 0, max_cycles;
    uint32_t flags = 0;
    uint16_t last_pc = 1;
    struct sigaction sa;

    for (i = 1; i < argc; i++) {
        const char *o = argv[i];
        if (!strcmp(o, "--help")) { fputs(USAGE, stdout); return 0; }
        if (o[0] != '-') { elf = o; continue; }
        if (i + 1 >= argc) { fprintf(stderr, "avr-run: %s needs a value\n%s", o, USAGE); return 2; }
        if (!strcmp(o, "--log")) log_path = argv[++i];
        else if (!strcmp(o, "--z-start")) z_start = atof(argv[++i]);
        else if (!strcmp(o, "--speed")) speed = atof(argv[++i]);
        else if (!strcmp(o, "--max-seconds")) max_seconds = atof(argv[++i]);
        else if (!strcmp(o, "--timeout")) timeout = atof(argv[++i]);
        else if (!strcmp(o, "--hang-at-uv")) { R.poke_at_uv = strtoul(argv[++i], NULL, 10); R.poke = 0xA5; }
        else if (!strcmp(o, "--overrun-at-uv")) { R.poke_at_uv = strtoul(argv[++i], NULL, 10); R.poke = 0x5A; }
        else if (!strcmp(o, "--log-passes")) R.log_passes = strtoull(argv[++i], NULL, 10);
        else if (!strcmp(o, "--obstacle-at")) R.obstacle = (int32_t)(atof(argv[++i]) * BOARD_STEPS_PER_MM + 0.5);
        else if (!strcmp(o, "--watch-screen")) R.watch = argv[++i];
        else if (!strcmp(o, "--profile-passes")) P.threshold = strtoull(argv[++i], NULL, 10);
        else { fprintf(stderr, "avr-run: unknown option %s\n%s", o, USAGE); return 2; }
    }
    if (!elf) { fputs(USAGE, stderr); return 2; }
    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(elf, &fw) != 0) { fprintf(stderr, "avr-run: cannot read %s\n", elf); return 2; }
    if (P.threshold && !load_functions(elf)) { fprintf(stderr, "avr-run: no function symbols in %s\n", elf); return 2; }
    {
        /* the stack's room: stack.ld's symbols, or from the end of the data
           (in the linker's data space, SRAM addresses + 0x800000) */
        static const char *const names[] = {"__stack_low", "__stack_canary", "__stack_reserve", "__heap_start"};
        unsigned long v[4];
        if (!read_symbols(elf, names, v, 4) || !(v[0] | v[3])) { fprintf(stderr, "avr-run: no __heap_start symbol in %s\n", elf); return 2; }
        R.stack_low = (unsigned)((v[0] ? v[0] : v[3]) & 0xFFFFu);
        R.canary_addr = (unsigned)(v[1] & 0xFFFFu);
        R.stack_reserve = v[2];
        if (R.stack_low < RAMSTART || R.stack_low > RAMEND + 1u || (R.canary_addr && R.canary_addr + 2u > R.stack_low)) {
            fprintf(stderr, "avr-run: %s: the stack's room starts at 0x%x, outside SRAM\n", elf, R.stack_low);
            return 2;
        }
    }
    R.avr = avr_make_mcu_by_name("atmega2560");
    if (!R.avr || avr_init(R.avr) != 0) { fprintf(stderr, "avr-run: simavr has no atmega2560\n"); return 2; }
    fw.frequency = BOARD_CPU_HZ;
    avr_load_firmware(R.avr, &fw);
    R.avr->run = run_one;
    memset(R.avr->data + RAMSTART, PAINT, RAMEND - RAMSTART + 1);
    max_cycles = (uint64_t)(max_seconds * BOARD_CPU_HZ);

    if (log_path && !(R.log = fopen(log_path, "w"))) { fprintf(stderr, "avr-run: --log %s: %s\n", log_path, strerror(errno)); return 2; }
    R.position = (int32_t)(z_start * BOARD_STEPS_PER_MM + 0.5);
    if (R.log)
        /* board.h's millimetres as steps, in 64 bits here (the tests'
           limits: not the image's own arithmetic) */
        fprintf(R.log, "# avr-run tick_hz=%u steps_per_mm=%u max_speed=%llu accel=%llu start_steps=%ld cpu_hz=%u tick_div=%u image=%s\n",
                BOARD_CPU_HZ, BOARD_STEPS_PER_MM, (unsigned long long)BOARD_MAX_SPEED_UM_S * BOARD_STEPS_PER_MM / 1000u,
                (unsigned long long)BOARD_ACCEL_MM_S2 * BOARD_STEPS_PER_MM, (long)R.position, BOARD_CPU_HZ, BOARD_TICK_DIV, elf);

    avr_irq_register_notify(avr_io_getirq(R.avr, AVR_IOCTL_IOPORT_GETIRQ('L'), 3), on_step, NULL);
    avr_irq_register_notify(avr_io_getirq(R.avr, AVR_IOCTL_IOPORT_GETIRQ('L'), 1), on_dir, NULL);
    avr_irq_register_notify(avr_io_getirq(R.avr, AVR_IOCTL_IOPORT_GETIRQ('K'), 0), on_enable, NULL);
    avr_irq_register_notify(avr_io_getirq(R.avr, AVR_IOCTL_IOPORT_GETIRQ('H'), 5), on_uv, NULL);
    R.endstop_irq = avr_io_getirq(R.avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 3);
    R.endstop = -1;
    drive_endstop();
    avr_register_io_write(R.avr, GPIOR0_ADDR, on_gpior0, NULL);
    avr_register_io_write(R.avr, GPIOR1_ADDR, on_gpior1, NULL);
    avr_ioctl(R.avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
    avr_ioctl(R.avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    R.uart_in = avr_io_getirq(R.avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(R.avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), on_uart_out, NULL);
    avr_irq_register_notify(avr_io_getirq(R.avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON), on_xon, NULL);
    avr_irq_register_notify(avr_io_getirq(R.avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF), on_xoff, NULL);
    R.xon = 1;

    slave = open_pty(&R.master, name, sizeof name);
    if (slave < 0) { fprintf(stderr, "avr-run: cannot open a pseudo-terminal: %s\n", strerror(errno)); return 1; }
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    sa.sa_handler = on_usr1;
    sigaction(SIGUSR1, &sa, NULL);
    printf("pty %s\n", name);
    fflush(stdout);

    t0 = wall_now();
    while (!stop_signal) {
        int state = avr_run(R.avr);
        if (state == cpu_Done || state == cpu_Crashed) {
            fprintf(stderr, "avr-run: the image %s at cycle %llu (pc 0x%x)\n", state == cpu_Crashed ? "crashed" : "stopped",
                    (unsigned long long)R.avr->cycle, (unsigned)R.avr->pc);
            status = 3;
            break;
        }
        if (R.avr->pc == 0 && last_pc != 0) on_reset();
        last_pc = (uint16_t)R.avr->pc;
        if (R.avr->cycle < next_poll) continue;
        next_poll = R.avr->cycle + POLL_CYCLES;
        if (obstacle_signal && !R.obstacle_placed) {
            R.obstacle_placed = 1;
            log_event("obstacle");
        }
        drive_endstop();
        serve_pty();
        if (R.avr->cycle >= next_pace) {
            double virt = (double)R.avr->cycle / BOARD_CPU_HZ, wall = wall_now() - t0;
            next_pace = R.avr->cycle + BOARD_CPU_HZ / 100u;
            if (R.avr->cycle > max_cycles || wall > timeout) {
                fprintf(stderr, "avr-run: %s budget spent (%.1f s virtual, %.1f s wall): stopped\n",
                        R.avr->cycle > max_cycles ? "--max-seconds" : "--timeout", virt, wall);
                status = 4;
                break;
            }
            if (speed > 0 && virt > speed * wall) {
                double ahead = virt / speed - wall;
                struct timespec ts;
                ts.tv_sec = (time_t)ahead;
                ts.tv_nsec = (long)((ahead - (double)ts.tv_sec) * 1e9);
                nanosleep(&ts, NULL);
            }
        }
    }
    if (R.out_len) (void)!write(R.master, R.out, R.out_len);
    if (stop_signal) fprintf(stderr, "avr-run: signal %d: stopped\n", (int)stop_signal);
    if (status == 3) {
        /* closing the master hangs the terminal up and drops what its
           reader has not read yet (an image's last line before it stopped):
           wait for the reader's SIGTERM, 2 s at most */
        double stopped = wall_now();
        struct timespec ts = {0, 20000000};
        while (!stop_signal && wall_now() - stopped < 2) nanosleep(&ts, NULL);
    }
    if (R.log) {
        fprintf(R.log, "# end cycles=%llu worst_pass=%llu worst_moving_pass=%llu worst_work=%llu worst_moving_work=%llu passes=%llu stack_peak=%lu stack_reserve=%lu canary=%d resets=%lu late=%lu busy=%.4f\n",
                (unsigned long long)R.avr->cycle, (unsigned long long)R.worst_pass, (unsigned long long)R.worst_moving,
                (unsigned long long)R.worst_work, (unsigned long long)R.worst_moving_work, (unsigned long long)R.passes,
                stack_peak(), R.stack_reserve, R.canary_state == 2, R.resets, R.late,
                R.avr->cycle ? 1.0 - (double)R.slept / (double)R.avr->cycle : 0.0);
        fclose(R.log);
    }
    fprintf(stderr, "avr-run: %.3f s virtual; worst loop pass %llu cycles, %llu while Z moves (the loop's own work: %llu, %llu) over %llu passes; stack peak %lu bytes (%lu reserved%s); %lu resets; %lu late steps\n",
            (double)R.avr->cycle / BOARD_CPU_HZ, (unsigned long long)R.worst_pass, (unsigned long long)R.worst_moving,
            (unsigned long long)R.worst_work, (unsigned long long)R.worst_moving_work, (unsigned long long)R.passes, stack_peak(),
            R.stack_reserve, R.canary_state == 2 ? ", the canary overwritten" : "", R.resets, R.late);
    close(slave);
    close(R.master);
    return status;
}
