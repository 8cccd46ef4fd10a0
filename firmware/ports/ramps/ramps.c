/* The RAMPS 1.4 / Arduino Mega 2560 board layer (board.h has the pin map).
   Timing is done by the timers' compare units, not by code:
     - Timer5 runs free at 2 MHz (prescaler 8) and is the tick; its overflow
       interrupt counts the upper bits. Each queued step is armed in OCR5A
       with COM5A "set on match", so the STEP pin rises in hardware at its
       tick; the compare interrupt then switches COM5A to "clear on match"
       STEP_PULSE ticks later and, once the pulse has ended, sets DIR and arms
       the next step. A step whose tick has passed before it could be armed
       is never sent: the queue is dropped and the step counted late.
     - Timer4 runs in step with Timer5 (both started together under GTCCR's
       TSM) and switches the UV MOSFET on and off with COM4C at the queued
       ticks, so an exposure's end does not wait for the main loop.
     - Timer3 (in step too) wakes the idle loop at its deadline.
   One invariant keeps the pins clean under simavr too: a compare unit's
   COM mode always matches its pin's level ("set on match" while low,
   "clear on match" while high, disconnected with PORT equal to the level
   while waiting). simavr 1.6 re-runs the timer setup on every OCR write and
   drives each connected OC pin to the level opposite its mode then; with
   the invariant that is the level the pin already has. A real ATmega2560
   does nothing on those writes, so the same code is right on both.
   Register names and bits are avr-libc's <avr/io.h> for the ATmega2560
   (datasheet sections 17, 22, 28, 12). File-static state here is the
   hardware's: one UART, one Z axis, one UV output. */
#include "board.h"
#include <avr/eeprom.h>
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>

/* ---- reset ---------------------------------------------------------------
   After a watchdog reset the watchdog stays enabled at its shortest period
   (16 ms) with WDRF set: clear MCUSR and stop it before the C runtime
   clears .bss (which can take longer). .init3 runs after r1 is zeroed. */
static uint8_t reset_cause __attribute__((section(".noinit")));
void ramps_init3(void) __attribute__((naked, used, section(".init3")));
void ramps_init3(void)
{
    GPIOR0 = BOARD_MARK_BOOT;
    reset_cause = MCUSR;
    MCUSR = 0;
    wdt_disable();
}

uint8_t board_reset_cause(void) { return reset_cause; }

/* ---- the tick ---------------------------------------------------------------- */
static volatile uint32_t wraps;

ISR(TIMER5_OVF_vect) { wraps++; }

/* Interrupts off. A wrap whose interrupt has not run yet belongs to this
   reading if the counter reads low. */
static uint32_t ticks32(void)
{
    uint16_t t = TCNT5;
    uint32_t w = wraps;
    if ((TIFR5 & _BV(TOV5)) && t < 0x8000u) w++;
    return (w << 16) | t;
}

uint64_t board_ticks(void)
{
    uint8_t sreg = SREG;
    uint16_t t;
    uint64_t w;
    cli();
    t = TCNT5;
    w = wraps;
    if ((TIFR5 & _BV(TOV5)) && t < 0x8000u) w++;
    SREG = sreg;
    return (w << 16) | t;
}

/* ---- steps --------------------------------------------------------------------- */
#define STEP_QUEUE 32u         /* a power of two */
#define STEP_PULSE 10u         /* ticks high: 5 us (A4988 needs 1 us, DRV8825 1.9 us) */
#define ARM_LEAD   24u         /* ticks: the least time from arming a compare to its match */
#define FAR        0xF000u     /* further than this: wait for the next pass of the counter */
#define COM5A_BITS (_BV(COM5A1) | _BV(COM5A0))
#define COM4C_BITS (_BV(COM4C1) | _BV(COM4C0))
enum { IDLE, WAIT, RISE, FALL };

static uint32_t step_tick[STEP_QUEUE];
static int8_t step_dir[STEP_QUEUE];
static volatile uint8_t step_head, step_tail, step_state;
static volatile uint16_t steps_late;

/* Interrupts off: arms the oldest queued step, or waits, or stops. */
static void step_arm(void)
{
    while (step_head != step_tail) {
        uint8_t i = step_tail % STEP_QUEUE;
        int32_t ahead = (int32_t)(step_tick[i] - ticks32());
        if (ahead < (int32_t)ARM_LEAD) {
            /* too late to be on time: never sent, the rest dropped with it */
            GPIOR0 = BOARD_MARK_LATE;
            steps_late = (uint16_t)(steps_late + (uint8_t)(step_head - step_tail));
            step_tail = step_head;
            break;
        }
        if (ahead >= (int32_t)FAR) {
            step_state = WAIT;
            TCCR5A &= (uint8_t)~COM5A_BITS; /* the pin follows PORTL3: low */
            OCR5A = (uint16_t)(TCNT5 + 0x8000u);
        } else {
            /* DIR, never writing PL3's PORT bit high (the pin is low now) */
            uint8_t l = (uint8_t)(PORTL & ~(_BV(PL1) | _BV(PL3)));
            PORTL = step_dir[i] > 0 ? (uint8_t)(l | _BV(PL1)) : l;
            TCCR5A |= COM5A_BITS; /* set on match, then the compare value */
            OCR5A = (uint16_t)step_tick[i];
            step_state = RISE;
            step_tail++;
        }
        TIFR5 = _BV(OCF5A);
        TIMSK5 |= _BV(OCIE5A);
        return;
    }
    step_state = IDLE;
    TIMSK5 &= (uint8_t)~_BV(OCIE5A);
    TCCR5A &= (uint8_t)~COM5A_BITS; /* the pin follows PORTL3: low */
}

ISR(TIMER5_COMPA_vect)
{
    if (step_state == RISE) {
        /* the pin went high at the match: clear it STEP_PULSE ticks on */
        uint16_t fall = (uint16_t)(OCR5A + STEP_PULSE);
        TCCR5A = (uint8_t)((TCCR5A & ~COM5A_BITS) | _BV(COM5A1));
        OCR5A = fall;
        if ((uint16_t)(TCNT5 - fall) < 0x8000u) OCR5A = (uint16_t)(TCNT5 + 2u); /* passed already */
        step_state = FALL;
        return;
    }
    step_arm(); /* FALL (the pulse is over) or WAIT */
}

int board_step_at(int dir, uint64_t when)
{
    uint8_t sreg = SREG, ok = 0;
    cli();
    if ((uint8_t)(step_head - step_tail) < STEP_QUEUE) {
        uint8_t i = step_head % STEP_QUEUE;
        step_tick[i] = (uint32_t)when;
        step_dir[i] = (int8_t)dir;
        step_head++;
        ok = 1;
        if (step_state == IDLE) step_arm();
    }
    SREG = sreg;
    return ok;
}

uint8_t board_step_room(void)
{
    return (uint8_t)(STEP_QUEUE - (uint8_t)(step_head - step_tail));
}

uint16_t board_step_late(void)
{
    uint16_t n;
    uint8_t sreg = SREG;
    cli();
    n = steps_late;
    SREG = sreg;
    return n;
}

void board_step_flush(void)
{
    uint8_t sreg = SREG;
    cli();
    step_tail = step_head;
    SREG = sreg;
}

int board_endstop(void) { return (PIND & _BV(PD3)) != 0; }

void board_motor(int on)
{
    if (on) PORTK &= (uint8_t)~_BV(PK0);
    else PORTK |= _BV(PK0);
}

/* ---- UV ------------------------------------------------------------------------------ */
#define UV_QUEUE 4u
static uint32_t uv_tick[UV_QUEUE];
static uint8_t uv_on[UV_QUEUE];
static volatile uint8_t uv_head, uv_tail, uv_state;

static uint8_t uv_level, uv_next;

/* Interrupts off. Between transitions COM4C is disconnected and PORTH5
   holds the level, so waiting (or a match) changes nothing. */
static void uv_hold(void)
{
    if (uv_level) PORTH |= _BV(PH5);
    else PORTH &= (uint8_t)~_BV(PH5);
    TCCR4A &= (uint8_t)~COM4C_BITS;
}

static void uv_arm(void)
{
    if (uv_head == uv_tail) {
        uv_state = IDLE;
        uv_hold();
        TIMSK4 &= (uint8_t)~_BV(OCIE4C);
        return;
    }
    {
        uint8_t i = uv_tail % UV_QUEUE;
        int32_t ahead = (int32_t)(uv_tick[i] - ticks32());
        if (uv_on[i] == uv_level) {
            /* no change: nothing to switch */
            uv_tail++;
            uv_arm();
            return;
        }
        if (ahead >= (int32_t)FAR) {
            uv_state = WAIT;
            uv_hold();
            OCR4C = (uint16_t)(TCNT4 + 0x8000u);
        } else {
            /* set on match while off, clear on match while on, then the value;
               a transition already due (a late "on", or "off" now) happens at once */
            TCCR4A = (uint8_t)((TCCR4A & ~COM4C_BITS) | (uv_level ? _BV(COM4C1) : COM4C_BITS));
            OCR4C = ahead < (int32_t)ARM_LEAD ? (uint16_t)(TCNT4 + 2u) : (uint16_t)uv_tick[i];
            uv_next = uv_on[i];
            uv_state = RISE;
            uv_tail++;
        }
    }
    TIFR4 = _BV(OCF4C);
    TIMSK4 |= _BV(OCIE4C);
}

ISR(TIMER4_COMPC_vect)
{
    if (uv_state == RISE) uv_level = uv_next; /* the pin switched at the match */
    uv_arm();
}

void board_uv_at(int on, uint64_t when)
{
    uint8_t sreg = SREG;
    cli();
    if ((uint8_t)(uv_head - uv_tail) == UV_QUEUE) uv_tail++; /* cannot happen: the core alternates */
    uv_tick[uv_head % UV_QUEUE] = (uint32_t)when;
    uv_on[uv_head % UV_QUEUE] = (uint8_t)(on != 0);
    uv_head++;
    if (uv_state == IDLE) uv_arm();
    SREG = sreg;
}

/* ---- UART0 ------------------------------------------------------------------------------ */
static uint8_t rx_buf[BOARD_RX_SIZE], tx_buf[BOARD_TX_SIZE];
static volatile uint16_t rx_head, rx_tail, tx_head, tx_tail, rx_lost, tx_lost;

ISR(USART0_RX_vect)
{
    uint8_t b = UDR0;
    uint16_t head = rx_head;
    if ((uint16_t)(head - rx_tail) == BOARD_RX_SIZE) { rx_lost++; return; }
    rx_buf[head % BOARD_RX_SIZE] = b;
    rx_head = (uint16_t)(head + 1u);
}

ISR(USART0_UDRE_vect)
{
    uint16_t tail = tx_tail;
    if (tail == tx_head) { UCSR0B &= (uint8_t)~_BV(UDRIE0); return; }
    UDR0 = tx_buf[tail % BOARD_TX_SIZE];
    tx_tail = (uint16_t)(tail + 1u);
}

size_t board_rx_peek(const uint8_t **data)
{
    uint16_t head, tail = rx_tail, to_end = (uint16_t)(BOARD_RX_SIZE - tail % BOARD_RX_SIZE), n;
    cli();
    head = rx_head;
    sei();
    n = (uint16_t)(head - tail);
    *data = rx_buf + tail % BOARD_RX_SIZE;
    return n < to_end ? n : to_end;
}

void board_rx_consume(size_t n)
{
    cli();
    rx_tail = (uint16_t)(rx_tail + n);
    sei();
}

void board_write(const uint8_t *data, size_t size)
{
    size_t i;
    for (i = 0; i < size; i++) {
        uint16_t head = tx_head;
        cli();
        if ((uint16_t)(head - tx_tail) == BOARD_TX_SIZE) { tx_lost++; sei(); continue; }
        sei();
        tx_buf[head % BOARD_TX_SIZE] = data[i];
        cli();
        tx_head = (uint16_t)(head + 1u);
        UCSR0B |= _BV(UDRIE0);
        sei();
    }
}

uint16_t board_rx_lost(void) { uint16_t n; cli(); n = rx_lost; sei(); return n; }
uint16_t board_tx_lost(void) { uint16_t n; cli(); n = tx_lost; sei(); return n; }

/* ---- idle, watchdog, EEPROM ------------------------------------------------------------------ */
/* The wake-up alarm is Timer3's compare A (Timer3 runs with 4 and 5): an
   OCR write on Timer5 itself made simavr miss the step compare's match. */
ISR(TIMER3_COMPA_vect) { TIMSK3 &= (uint8_t)~_BV(OCIE3A); }

void board_idle(uint64_t deadline)
{
    uint64_t now;
    cli();
    now = board_ticks();
    if (rx_head != rx_tail || now >= deadline) { sei(); return; }
    if (deadline - now < FAR) {
        OCR3A = (uint16_t)deadline;
        TIFR3 = _BV(OCF3A);
        TIMSK3 |= _BV(OCIE3A);
    }
    GPIOR0 = BOARD_MARK_IDLE;
    /* sei's next instruction runs before any interrupt: none is missed
       between the checks and sleep; the overflow wakes it within 33 ms */
    sleep_enable();
    sei();
    sleep_cpu();
    sleep_disable();
}

void board_watchdog(void) { wdt_reset(); }

static uint32_t boots;
uint32_t board_boot_count(void) { return boots; }

static uint32_t rows_counted;
static uint8_t shown;
void board_mask_row(void) { rows_counted++; }
void board_show(int slot)
{
    shown = (uint8_t)(slot + 1);
    GPIOR1 = shown;
}

#if BOARD_WDT_MS == 120u
#define WDT_PERIOD WDTO_120MS
#elif BOARD_WDT_MS == 250u
#define WDT_PERIOD WDTO_250MS
#else
#error "BOARD_WDT_MS: 120 or 250"
#endif

void board_init(void)
{
    uint32_t *const counter = (uint32_t *)0;
    uint32_t was;
    /* pins: STEP and DIR low, the driver off, UV off, the endstop pulled up */
    PORTL &= (uint8_t)~(_BV(PL3) | _BV(PL1));
    DDRL |= _BV(PL3) | _BV(PL1);
    PORTK |= _BV(PK0);
    DDRK |= _BV(PK0);
    PORTH &= (uint8_t)~_BV(PH5);
    DDRH |= _BV(PH5);
    DDRD &= (uint8_t)~_BV(PD3);
    PORTD |= _BV(PD3);
    /* Timers 3, 4 and 5 at clk/8, started together */
    GTCCR = _BV(TSM) | _BV(PSRSYNC);
    TCCR5A = 0;
    TCCR5B = _BV(CS51);
    TCCR4A = 0;
    TCCR4B = _BV(CS41);
    TCCR3A = 0;
    TCCR3B = _BV(CS31);
    TCNT5 = 0;
    TCNT4 = 0;
    TCNT3 = 0;
    GTCCR = 0;
    TIMSK5 = _BV(TOIE5);
    /* UART0: 8N1, double speed */
    UBRR0 = (uint16_t)(BOARD_CPU_HZ / 8u / BOARD_BAUD - 1u);
    UCSR0A = _BV(U2X0);
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
    UCSR0B = _BV(RXCIE0) | _BV(RXEN0) | _BV(TXEN0);
    /* the boot counter: an erased EEPROM reads all ones */
    was = eeprom_read_dword(counter);
    boots = (was == 0xFFFFFFFFu ? 0u : was) + 1u;
    eeprom_update_dword(counter, boots);
    set_sleep_mode(SLEEP_MODE_IDLE);
    wdt_enable(WDT_PERIOD);
    sei();
}
