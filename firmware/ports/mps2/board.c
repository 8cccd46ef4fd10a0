/* The mps2-an385 board as QEMU models it: a Cortex-M3 at 25 MHz, CMSDK UART0
   (0x40004000, receive interrupt IRQ 0, transmit IRQ 1) to the host, CMSDK
   timer 0 (0x40000000, IRQ 8) as the wake-up alarm, SysTick as the tick, the
   CMSDK watchdog (0x40008000, on the NMI: QEMU 7.2's mps2.c instantiates it
   on the an385, `info qtree` shows it), and ARM semihosting to leave QEMU
   with an exit status. Register layouts are from
   ARM's CMSDK technical reference (DDI 0479); QEMU's behaviour as measured
   (the team's emulation notes). */
#include "../cm3/cm3.h"
#include "board.h"

#define UART0_DATA     CM3_REG(0x40004000u)
#define UART0_STATE    CM3_REG(0x40004004u)
#define UART0_CTRL     CM3_REG(0x40004008u)
#define UART0_INTCLEAR CM3_REG(0x4000400Cu)
#define UART0_BAUDDIV  CM3_REG(0x40004010u)
#define UART_STATE_TX_FULL 1u
#define UART_STATE_RX_FULL 2u
#define UART_CTRL_TX_EN    1u
#define UART_CTRL_RX_EN    2u
#define UART_CTRL_TX_IRQ   4u
#define UART_CTRL_RX_IRQ   8u
#define UART_INT_TX        1u
#define UART_INT_RX        2u
#define UART0_RX_IRQ 0u
#define UART0_TX_IRQ 1u

#define TIMER0_CTRL     CM3_REG(0x40000000u)
#define TIMER0_VALUE    CM3_REG(0x40000004u)
#define TIMER0_RELOAD   CM3_REG(0x40000008u)
#define TIMER0_INTCLEAR CM3_REG(0x4000000Cu)
#define TIMER_CTRL_EN  1u
#define TIMER_CTRL_IRQ 8u
#define TIMER0_IRQ 8u

/* timer 1: the step alarm */
#define TIMER1_CTRL     CM3_REG(0x40001000u)
#define TIMER1_VALUE    CM3_REG(0x40001004u)
#define TIMER1_RELOAD   CM3_REG(0x40001008u)
#define TIMER1_INTCLEAR CM3_REG(0x4000100Cu)
#define TIMER1_IRQ 9u

/* the dual timer's first counter (DDI 0479, "APB dual-input timers"): the UV
   alarm; one-shot, 32-bit, interrupt enabled, enabled */
#define DUAL1_LOAD     CM3_REG(0x40002000u)
#define DUAL1_CTRL     CM3_REG(0x40002008u)
#define DUAL1_INTCLEAR CM3_REG(0x4000200Cu)
#define DUAL_CTRL_ONESHOT 1u
#define DUAL_CTRL_32BIT   2u
#define DUAL_CTRL_IRQ     0x20u
#define DUAL_CTRL_EN      0x80u
#define DUAL_IRQ 10u

/* The APB watchdog (DDI 0479, "APB watchdog"): counts WDOGLOAD down at the
   core clock; at zero it raises its interrupt (the NMI here) and reloads; at
   zero again with the interrupt still set it asserts reset (RESEN). A write
   to WDOGINTCLR clears the interrupt and reloads the count. Its registers
   take writes only after WDOGLOCK is given 0x1ACCE551. */
#define WDOG_LOAD    CM3_REG(0x40008000u)
#define WDOG_CONTROL CM3_REG(0x40008008u)
#define WDOG_INTCLR  CM3_REG(0x4000800Cu)
#define WDOG_LOCK    CM3_REG(0x40008C00u)
#define WDOG_CONTROL_INTEN 1u
#define WDOG_CONTROL_RESEN 2u
#define WDOG_UNLOCK 0x1ACCE551u

typedef char tx_ring_holds_the_window[CM3_TX_SIZE >= BOARD_TX_WORST ? 1 : -1];

#define BAUD 115200u /* QEMU ignores it; a real CMSDK UART needs it */

/* ---- semihosting ---------------------------------------------------------- */
static uint32_t semihost(uint32_t op, const void *arg)
{
    /* bkpt 0xab with the operation in r0 and its argument block in r1: QEMU
       (-semihosting-config enable=on) traps it; r0 comes back as the result. */
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}
#define SYS_OPEN   0x01u
#define SYS_CLOSE  0x02u
#define SYS_WRITE0 0x04u
#define SYS_WRITE  0x05u

static void safe_outputs(void);

#ifdef CM3_TRACE
/* ---- the timing trace (test images only, -DCM3_TRACE) ------------------------
   Every step (its scheduled tick, and cm3_ticks() when its alarm's
   interrupt ran) and every UV edge, as 16-byte records in RAM past the
   image's 20 KiB: QEMU's an385 has 4 MiB there, a real part has not, so
   only a test image may do this. Nothing is formatted or written while the
   firmware runs: at exit (board_exit) the records go to the host file
   MPS2_TRACE_FILE (semihosting SYS_OPEN/SYS_WRITE, relative to QEMU's
   directory), costing no emulated time, and one summary line goes to
   QEMU's stderr. The count lives in .bss, so a reset starts a new trace. */
#define MPS2_TRACE_FILE "fw-mps2-trace.bin"
#define TRACE_BASE 0x20100000u
#define TRACE_MAX (0x00300000u / sizeof(mps2_trace_record)) /* up to 0x20400000 */
typedef struct mps2_trace_record {
    uint64_t tick;   /* steps: the scheduled tick; UV: when it changed */
    uint32_t late;   /* steps: the interrupt's tick minus the scheduled one */
    int32_t kind;    /* MPS2_TRACE_*: +1 / -1 a step up / down */
} mps2_trace_record;
enum { MPS2_TRACE_UV_OFF = 2, MPS2_TRACE_UV_ON = 3 };
#define trace ((mps2_trace_record *)TRACE_BASE)
static uint32_t trace_count, trace_lost;
static uint64_t trace_sched, trace_emitted, pins_uv_off;

static void trace_event(int32_t kind, uint64_t tick, uint32_t late)
{
    if (trace_count == TRACE_MAX) { trace_lost++; return; }
    trace[trace_count].tick = tick;
    trace[trace_count].late = late;
    trace[trace_count].kind = kind;
    trace_count++;
}

void board_trace_step(uint64_t scheduled, uint64_t emitted)
{
    trace_sched = scheduled;
    trace_emitted = emitted;
}

/* prefix, then `value` in decimal, to QEMU's stderr */
void board_trace_text(const char *prefix, uint64_t value)
{
    char line[96], digits[24];
    size_t n = 0, d = 0;
    while (*prefix && n < 64) line[n++] = *prefix++;
    do digits[d++] = (char)('0' + value % 10u); while ((value /= 10u) != 0);
    while (d) line[n++] = digits[--d];
    line[n++] = '\n';
    line[n] = 0;
    (void)semihost(SYS_WRITE0, line);
}

static void trace_report(void)
{
    static const char name[] = MPS2_TRACE_FILE;
    uint32_t open_args[3], write_args[3], handle, i, steps = 0;
    uint64_t worst = 0;
    open_args[0] = (uint32_t)(uintptr_t)name;
    open_args[1] = 5u; /* "wb" */
    open_args[2] = sizeof name - 1u;
    handle = semihost(SYS_OPEN, open_args);
    if (handle != 0xFFFFFFFFu) {
        write_args[0] = handle;
        write_args[1] = TRACE_BASE;
        write_args[2] = trace_count * (uint32_t)sizeof(mps2_trace_record);
        (void)semihost(SYS_WRITE, write_args);
        (void)semihost(SYS_CLOSE, &handle);
    }
    for (i = 0; i < trace_count; i++)
        if (trace[i].kind == 1 || trace[i].kind == -1) {
            steps++;
            if (trace[i].late > worst) worst = trace[i].late;
        }
    board_trace_text("fw-mps2: trace steps ", steps);
    board_trace_text("fw-mps2: trace records lost ", trace_lost);
    board_trace_text("fw-mps2: worst step lateness (cycles) ", worst);
    board_trace_text("fw-mps2: worst loop pass (cycles) ", cm3_worst_pass);
    board_trace_text("fw-mps2: worst loop pass while Z moves (cycles) ", cm3_worst_moving_pass);
    board_trace_text("fw-mps2: the loop's own work, worst pass (cycles) ", cm3_worst_work);
    board_trace_text("fw-mps2: the loop's own work, worst pass while Z moves (cycles) ", cm3_worst_moving_work);
    board_trace_text("fw-mps2: passes whose interrupts outran them ", cm3_miscounted_passes);
    board_trace_text("fw-mps2: stack used (bytes) ", cm3_stack_used());
    board_trace_text("fw-mps2: replies dropped ", cm3_tx_dropped());
}
#endif

void board_exit(int code)
{
    /* SYS_EXIT_EXTENDED with ADP_Stopped_ApplicationExit: QEMU exits with
       `code` (plain SYS_EXIT cannot carry one on 32-bit ARM). */
    uint32_t block[2];
    uint64_t until = cm3_ticks() + BOARD_CLOCK_HZ / 20u;
    safe_outputs();
    /* the last reply (EXIT's ACK) out of the ring first, for up to 50 ms: the
       transmit interrupt sends it unless a fault has interrupts held */
    while (!cm3_tx_empty() && cm3_ticks() < until) {}
#ifdef CM3_TRACE
    trace_report();
#endif
    block[0] = 0x20026u;
    block[1] = (uint32_t)code;
    semihost(0x20u, block);
    for (;;) {}
}

void board_fault(int why)
{
    safe_outputs(); /* UV off, Z disabled, first */
    /* SYS_WRITE0 to QEMU's stderr, so a failing test says what happened. */
    semihost(SYS_WRITE0, why == CM3_FAULT_STACK ? "fw-mps2: stack overflow (canary overwritten)\n"
                                           : "fw-mps2: hard fault\n");
    board_exit(MPS2_EXIT_FAULT + why);
}

/* ---- UART ------------------------------------------------------------------ */
#ifdef CM3_TRACE
#define ISR_ENTER() cm3_trace_isr_enter()
#define ISR_LEAVE() cm3_trace_isr_leave()
#else
#define ISR_ENTER() do {} while (0)
#define ISR_LEAVE() do {} while (0)
#endif

void uart0_rx_handler(void);
void uart0_rx_handler(void)
{
    ISR_ENTER();
    /* Cleared before reading: a byte that lands while we read raises it again. */
    UART0_INTCLEAR = UART_INT_RX;
    while (UART0_STATE & UART_STATE_RX_FULL) {
        if (cm3_rx_full()) {
            cm3_rx_stall();
            break;
        }
        cm3_rx_push((uint8_t)UART0_DATA);
    }
    ISR_LEAVE();
}

void board_rx_resume(void)
{
    cm3_irq_pend(UART0_RX_IRQ);
}

/* Bytes while the UART takes them: the TX interrupt comes when TX-full
   goes from set to clear, so a UART whose one-byte buffer is still full
   takes one an interrupt; QEMU's empties at once while the pty takes bytes,
   so one interrupt sends a whole reply (an interrupt a byte would make a
   STATUS reply cost a large share of a step interval). Its priority is
   below the alarms', so steps go out meanwhile. */
void uart0_tx_handler(void);
void uart0_tx_handler(void)
{
    uint8_t byte;
    ISR_ENTER();
    UART0_INTCLEAR = UART_INT_TX;
    while (!(UART0_STATE & UART_STATE_TX_FULL) && cm3_tx_pop(&byte)) UART0_DATA = byte;
    ISR_LEAVE();
}

void board_write(const uint8_t *data, size_t size)
{
    (void)cm3_tx_write(data, size);
    /* the interrupt takes the first byte: with the UART idle no edge would
       raise it (and a byte in flight raises it again when done) */
    cm3_irq_pend(UART0_TX_IRQ);
}

/* ---- the watchdog -----------------------------------------------------------
   Started by the first refresh (fw_run's first pass), so that an image that
   never runs the core (the planner bench) is not reset. */
static int watchdog_on;

void board_watchdog(void)
{
    WDOG_LOCK = WDOG_UNLOCK;
    if (!watchdog_on) {
        WDOG_LOAD = BOARD_CLOCK_HZ / 1000u * BOARD_WATCHDOG_MS;
        WDOG_CONTROL = WDOG_CONTROL_INTEN | WDOG_CONTROL_RESEN;
        watchdog_on = 1;
    }
    WDOG_INTCLR = 1u;
    WDOG_LOCK = 0;
}

/* The watchdog's first expiry: the loop has not refreshed it for
   BOARD_WATCHDOG_MS. Light off and motor off at once, then a system reset
   (AIRCR SYSRESETREQ: QEMU restarts the image; with -no-reboot it exits);
   the watchdog's own reset at its second expiry is the backstop. */
void board_nmi(void)
{
    safe_outputs();
#ifdef CM3_TRACE
    board_trace_text("fw-mps2: watchdog expired at tick ", cm3_ticks());
    board_trace_text("fw-mps2: the UV light went off at tick ", pins_uv_off);
#endif
    SCB_AIRCR = SCB_AIRCR_SYSRESETREQ;
    for (;;) {}
}

/* ---- the wake-up alarm -------------------------------------------------------
   Timer 0 runs at the core clock like the tick, so a delay in ticks is a
   count. It only wakes the loop, which then reads the absolute tick: the
   restart of the count on a reload write (notes, pitfall 5) costs nothing. */
void timer0_handler(void);
void timer0_handler(void)
{
    ISR_ENTER();
    TIMER0_INTCLEAR = 1u;
    TIMER0_CTRL = 0;
    cm3_wake();
    ISR_LEAVE();
}

void board_wake_at(uint64_t deadline, uint64_t now)
{
    uint64_t delay = deadline - now;
    TIMER0_CTRL = 0;
    TIMER0_INTCLEAR = 1u;
    if (deadline == UINT64_MAX) return; /* FW_NEVER: only a byte can wake us */
    if (delay > 0xFFFFFFFFu) delay = 0xFFFFFFFFu; /* 171 s; the loop re-arms */
    TIMER0_RELOAD = (uint32_t)delay;
    TIMER0_VALUE = (uint32_t)delay;
    TIMER0_CTRL = TIMER_CTRL_EN | TIMER_CTRL_IRQ;
}

/* ---- the alarms: timer 1 for steps, the dual timer for the UV light --------- */
void timer1_handler(void);
void timer1_handler(void)
{
    ISR_ENTER();
    TIMER1_INTCLEAR = 1u;
    TIMER1_CTRL = 0;
    cm3_alarm(CM3_ALARM_STEP);
    ISR_LEAVE();
}

void dualtimer_handler(void);
void dualtimer_handler(void)
{
    ISR_ENTER();
    DUAL1_INTCLEAR = 1u;
    DUAL1_CTRL = 0;
    cm3_alarm(CM3_ALARM_UV);
    ISR_LEAVE();
}

void board_alarm(int which, uint64_t delay)
{
    uint32_t count = delay > 0xFFFFFFFFu ? 0xFFFFFFFFu : (uint32_t)delay;
    if (which == CM3_ALARM_STEP) {
        TIMER1_CTRL = 0;
        TIMER1_INTCLEAR = 1u;
        if (!count) return;
        TIMER1_RELOAD = count;
        TIMER1_VALUE = count;
        TIMER1_CTRL = TIMER_CTRL_EN | TIMER_CTRL_IRQ;
    } else {
        DUAL1_CTRL = 0;
        DUAL1_INTCLEAR = 1u;
        if (!count) return;
        DUAL1_LOAD = count;
        DUAL1_CTRL = DUAL_CTRL_ONESHOT | DUAL_CTRL_32BIT | DUAL_CTRL_IRQ | DUAL_CTRL_EN;
    }
}

void board_init(void)
{
#ifdef CM3_TRACE
    board_trace_text("fw-mps2: boot, watchdog period (ms) ", BOARD_WATCHDOG_MS);
#endif
    UART0_BAUDDIV = BOARD_CLOCK_HZ / BAUD;
    UART0_CTRL = UART_CTRL_TX_EN | UART_CTRL_RX_EN | UART_CTRL_RX_IRQ | UART_CTRL_TX_IRQ;
    /* the alarms above the UART and the wake-up timer: a step is never held
       behind a byte */
    cm3_irq_priority(UART0_RX_IRQ, CM3_PRIORITY_LOW);
    cm3_irq_priority(UART0_TX_IRQ, CM3_PRIORITY_LOW);
    cm3_irq_priority(TIMER0_IRQ, CM3_PRIORITY_LOW);
    cm3_irq_enable(UART0_RX_IRQ);
    cm3_irq_enable(UART0_TX_IRQ);
    cm3_irq_enable(TIMER0_IRQ);
    cm3_irq_enable(TIMER1_IRQ);
    cm3_irq_enable(DUAL_IRQ);
    cm3_tick_start();
}

/* ---- the printer's pins ------------------------------------------------------
   QEMU models no GPIO on this board, so the pins are a software model like
   the simulator's: the carriage starts MPS2_Z_START_MM above the endstop,
   which is closed while it is at or below its switching point, and the
   steps, the light and the masks shown are counted. The display buffers are
   not kept (20 KiB could not hold them): the core checks each mask's CRC-32
   as it decodes, which is what a test needs to know. */
static struct {
    int32_t true_position;     /* steps above the endstop's switching point */
    uint32_t steps, rows, shows;
    int uv, motor, shown;
} pins = {(int32_t)(MPS2_Z_START_MM * BOARD_STEPS_PER_MM), 0, 0, 0, 0, 0, -1};

void board_step(int dir)
{
#ifdef CM3_TRACE
    trace_event(dir, trace_sched, (uint32_t)(trace_emitted - trace_sched));
#endif
    pins.true_position += dir;
    pins.steps++;
}
int board_endstop(void) { return pins.true_position <= 0; }
void board_uv(int on)
{
#ifdef CM3_TRACE
    if (on != pins.uv) {
        uint64_t now = cm3_ticks();
        if (!on) pins_uv_off = now;
        trace_event(on ? MPS2_TRACE_UV_ON : MPS2_TRACE_UV_OFF, now, 0);
    }
#endif
    pins.uv = on;
}
void board_motor(int on) { pins.motor = on; }

static void safe_outputs(void)
{
    board_uv(0);
    board_motor(0);
}
void board_show(int slot) { pins.shown = slot; if (slot >= 0) pins.shows++; }

void board_mask_row(int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    (void)slot;
    (void)y;
    (void)row;
    (void)size;
    pins.rows++;
}

/* ---- the interrupt vectors ------------------------------------------------------ */
#define F cm3_fault_handler
CM3_IRQ_VECTORS irq_vectors[32] = { /* the an385's external interrupts */
    uart0_rx_handler, uart0_tx_handler, F, F, F, F, F, F, timer0_handler, timer1_handler, dualtimer_handler, F, F, F, F, F,
    F, F, F, F, F, F, F, F, F, F, F, F, F, F, F, F
};
#undef F
