/* The STM32F103C8 board ("blue pill" class): pins and clock, for its port.

   Pins:
     PA9   USART1 TX  -> host's RX (3.3 V levels; a USB-serial adapter)
     PA10  USART1 RX  <- host's TX (pulled up so a loose wire reads idle)
     PB12  STEP       stepper driver step input, a >= 2 us high pulse per step
     PB13  DIR        high = up (+1), set >= 1 us before the pulse
     PB14  ENABLE     low = driver enabled (A4988 / DRV8825 / TMC2209 EN)
     PB15  UV         high = UV light source on (the LED driver's enable)
     PB11  ENDSTOP    input with pull-up: a normally open switch to ground,
                      so closed (at the bottom) reads low
     PC13  LED        the board's LED, low = on: lit after a fault
   At reset every pin is a floating input until board_init drives UV low and
   ENABLE high (light off, motor free) before making them outputs: the UV
   and ENABLE lines need external pull-down / pull-up resistors for the
   microseconds before that. */
#ifndef FW_STM32F103_BOARD_H
#define FW_STM32F103_BOARD_H
#include <stdint.h>

#define STM32_CLOCK_HZ 72000000u /* SYSCLK = HSE 8 MHz x 9 (PLL) */

void board_step(int dir);
int board_endstop(void);
void board_uv(int on);
void board_motor(int on);
#endif
