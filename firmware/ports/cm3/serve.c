/* The loop fw.h asks of a port, on a Cortex-M3 board. */
#include "cm3.h"
#include "../../fw.h"

/* Bytes handed to the core at a time: between chunks the loop looks at the
   clock, so a long burst from the host delays a due step by at most the
   core's work on this many bytes, a small share of a step interval at the
   top speed (tests/test_qemu_timing.c holds every pass under one). */
#define CHUNK 32u

#ifdef CM3_TRACE
uint64_t cm3_worst_pass;        /* ticks of the longest pass (idle left out), its interrupts in */
uint64_t cm3_worst_moving_pass; /* the same while Z moves */
uint64_t cm3_worst_work;        /* the longest pass with its interrupts' ticks out: the loop's own work */
uint64_t cm3_worst_moving_work; /* the same while Z moves */
uint64_t cm3_miscounted_passes; /* passes whose interrupts' ticks outran the pass: the count is wrong */
/* Read whole (two words on this core), and in the order that keeps every
   interrupt counted inside the pass also inside its ticks: a pass's own
   work is never under-stated. */
static uint64_t isr_ticks(void)
{
    uint64_t a, b;
    do { a = cm3_isr_ticks; b = cm3_isr_ticks; } while (a != b);
    return a;
}
#define PASS_END()                                                                                      \
    do {                                                                                                \
        uint64_t i_ = isr_ticks() - pass_isr, t_ = cm3_ticks() - pass_start, w_ = t_ - i_;             \
        if (i_ > t_) { cm3_miscounted_passes++; w_ = t_; }                                              \
        int m_ = moving || fw_axis_busy(&fw->axis) || fw->steps.head != fw->steps.tail;                 \
        if (t_ > cm3_worst_pass) cm3_worst_pass = t_;                                                   \
        if (w_ > cm3_worst_work) cm3_worst_work = w_;                                                   \
        if (m_ && t_ > cm3_worst_moving_pass) cm3_worst_moving_pass = t_;                               \
        if (m_ && w_ > cm3_worst_moving_work) cm3_worst_moving_work = w_;                               \
    } while (0)
#else
#define PASS_END() do {} while (0)
#endif

void cm3_serve(fw_state *fw)
{
    uint64_t deadline = 0;
    for (;;) {
        const uint8_t *data;
        size_t n = cm3_rx_peek(&data);
        uint64_t now;
        int idle;
#ifdef CM3_TRACE
        uint64_t pass_start = cm3_ticks(), pass_isr = isr_ticks();
        int moving = fw_axis_busy(&fw->axis) || fw->steps.head != fw->steps.tail;
#endif
        if (!cm3_stack_ok()) board_fault(CM3_FAULT_STACK);
#ifdef CM3_HANG_LAYER
        /* the watchdog test's image: the loop stops dead in this layer's
           exposure, interrupts still on (the UV alarm, the watchdog's NMI) */
        if (fw->layer == CM3_HANG_LAYER && fw->uv_on) {
            board_trace_text("fw-mps2: loop hung in the exposure of layer ", fw->layer);
            board_trace_text("fw-mps2: hung at tick ", cm3_ticks());
            for (;;) {}
        }
#endif
        if (n) {
            if (n > CHUNK) n = CHUNK;
            n = fw_receive(fw, data, n, cm3_ticks());
            cm3_rx_consume(n);
            /* fw_receive returns no deadline, and what the bytes started
               (a move, an exposure) may be due before the old one */
            deadline = 0;
        }
        now = cm3_ticks();
        idle = now < deadline && !n;
        if (now >= deadline) deadline = fw_run(fw, now);
        PASS_END();
        if (idle) cm3_idle(deadline);
    }
}

void cm3_z_config(fw_config *config, uint32_t tick_hz, uint32_t steps_per_mm)
{
    config->tick_hz = tick_hz;
    config->axis.steps_per_mm = steps_per_mm;
    config->axis.max_speed = 10u * steps_per_mm;
    config->axis.accel = 50u * steps_per_mm;
    config->axis.home_speed = 5u * steps_per_mm;
    config->axis.max_steps = (int32_t)(200u * steps_per_mm);
    config->axis.home_travel = (int32_t)(220u * steps_per_mm);
    config->link_timeout_ms = 1000;
}
