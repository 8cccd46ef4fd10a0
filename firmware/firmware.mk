# The firmware images: included by the top Makefile, which sets B, CC, CSTD,
# CFLAGS, ARM_CC and the objs function.
#   $(B)/fw-sim               the core on a pseudo-terminal (ports/sim)
#   $(B)/fw-mps2.elf          the Cortex-M3 image QEMU's mps2-an385 runs
#   $(B)/fw-mps2-busy.elf     the same, idling by spinning: for -icount runs
#                             (a core asleep in WFI there can wake a period late)
#   $(B)/fw-mps2-trace.elf    the busy image that also records every step's
#                             scheduled and emitted tick and the worst loop
#                             pass (-DCM3_TRACE, tests/test_qemu_timing.c)
#   $(B)/fw-mps2-hang.elf     the trace image whose loop hangs in layer 2's
#                             exposure: the watchdog test
#   $(B)/fw-stm32f103.elf     an STM32F103C8 printer board, built, not run
#   $(B)/fw-ramps.elf         RAMPS 1.4 on an Arduino Mega 2560 (ATmega2560)
#   $(B)/fw-ramps-test.elf    the same for the simavr tests: a 240 x 200 display
#                             (small masks over a real-time UART) and a hang hook
#   firmware                  all of them, and each image's flash and RAM;
#                             fails if a Cortex-M3 image needs more than 20 KiB
#                             of RAM or the Mega's more than 8 KiB

# The core every port links: adaslice_fw.c is adaslice_mcu.h's implementation.
FW_CORE_SRC = firmware/core.c firmware/motion.c firmware/gcode.c link/frame.c link/messages.c firmware/adaslice_fw.c
FW_HDRS     = $(wildcard firmware/*.h) $(wildcard link/*.h) adaslice_mcu.h
FW_CM3      = firmware/ports/cm3
FW_CM3_SRC  = $(FW_CM3)/cm3.c $(FW_CM3)/serve.c
FW_CM3_HDRS = $(FW_CM3)/cm3.h
FW_RAM_MAX  = 20480

ARM_SIZE ?= arm-none-eabi-size
ARM_NM   ?= arm-none-eabi-nm
# No C library: cm3.c has the few functions gcc and the core call; libgcc
# for 64-bit division. Loop-to-memset rewriting is off so that memset itself
# cannot become a call to memset.
FW_ARM_FLAGS = -mcpu=cortex-m3 -mthumb -Os -std=c99 -Wall -Wextra -Wpedantic -Werror \
               -ffreestanding -fno-tree-loop-distribute-patterns -ffunction-sections -fdata-sections \
               -nostdlib -Wl,--gc-sections
FW_ARM_LIBS  = -lgcc
# 1536 bytes of stack (the linker scripts' default is 2048): the trace image
# paints it and reports how deep a print under QEMU (planned by the
# printer, masks streaming, steps and replies from interrupts) went
# (tests/test_qemu_timing.c prints it); the rest of the 20 KiB holds the
# transmit ring. The canary still guards it.
FW_ARM_FLAGS += -Wl,--defsym=STACK_SIZE=1536

.PHONY: firmware

$(B)/fw-sim: $(call objs,rel,firmware/ports/sim/sim.c link/tty.c $(FW_CORE_SRC))
	$(CC) $(CFLAGS) $^ -o $@ -lm

# A Cortex-M3 image: cm3/main.c with the board's board.h, its board.c and
# linker script.
FW_MPS2 = firmware/ports/mps2
FW_MPS2_SRC = $(FW_CM3)/main.c $(FW_MPS2)/board.c $(FW_CM3_SRC) $(FW_CORE_SRC)
FW_MPS2_DEPS = $(FW_MPS2_SRC) $(FW_MPS2)/board.h $(FW_MPS2)/mps2.ld $(FW_CM3_HDRS) $(FW_HDRS)

# The transmit ring (1024 bytes by default) holds the replies to the
# window's 4 frames, up to 255 bytes each (board.h).
FW_MPS2_FLAGS = $(FW_ARM_FLAGS)

$(B)/fw-mps2.elf: $(FW_MPS2_DEPS)
	@mkdir -p $(B)
	$(ARM_CC) $(FW_MPS2_FLAGS) -I$(FW_MPS2) -T $(FW_MPS2)/mps2.ld $(FW_MPS2_SRC) -o $@ $(FW_ARM_LIBS)

$(B)/fw-mps2-busy.elf: $(FW_MPS2_DEPS)
	@mkdir -p $(B)
	$(ARM_CC) $(FW_MPS2_FLAGS) -DCM3_BUSY_WAIT -I$(FW_MPS2) -T $(FW_MPS2)/mps2.ld $(FW_MPS2_SRC) -o $@ $(FW_ARM_LIBS)

$(B)/fw-mps2-trace.elf: $(FW_MPS2_DEPS)
	@mkdir -p $(B)
	$(ARM_CC) $(FW_MPS2_FLAGS) -DCM3_BUSY_WAIT -DCM3_TRACE -I$(FW_MPS2) -T $(FW_MPS2)/mps2.ld $(FW_MPS2_SRC) -o $@ $(FW_ARM_LIBS)

$(B)/fw-mps2-hang.elf: $(FW_MPS2_DEPS)
	@mkdir -p $(B)
	$(ARM_CC) $(FW_MPS2_FLAGS) -DCM3_BUSY_WAIT -DCM3_TRACE -DCM3_HANG_LAYER=2 -I$(FW_MPS2) -T $(FW_MPS2)/mps2.ld $(FW_MPS2_SRC) \
	    -o $@ $(FW_ARM_LIBS)

# The receive ring holds the protocol's window of 4 full frames (4 x 255
# bytes): a real USART cannot hold the line the way QEMU's does; the
# transmit ring the 4 replies of up to 255 bytes they may draw. A display
# row is 2560 / 8 = 320 bytes (FW_ROW_BYTES; the core's default is 480).
FW_STM32 = firmware/ports/stm32f103
FW_STM32_SRC = $(FW_CM3)/main.c $(FW_STM32)/board.c $(FW_CM3_SRC) $(FW_CORE_SRC)

$(B)/fw-stm32f103.elf: $(FW_STM32_SRC) $(FW_STM32)/board.h $(FW_STM32)/stm32f103.ld $(FW_CM3_HDRS) $(FW_HDRS)
	@mkdir -p $(B)
	$(ARM_CC) $(FW_ARM_FLAGS) -DCM3_RX_SIZE=1024u -DCM3_TX_SIZE=1024u -DBOARD_WINDOW=4u -DFW_ROW_BYTES=320u -I$(FW_STM32) -T $(FW_STM32)/stm32f103.ld \
	    $(FW_STM32_SRC) -o $@ $(FW_ARM_LIBS)

# The planner bench image: the mps2 board code and cm3 reset/tick with its
# own main, built as the firmware is (-Os, 20 KiB of RAM by mps2.ld).
BENCH_PLAN_SRC = bench/mcu_plan_mps2.c $(FW_MPS2)/board.c $(FW_CM3)/cm3.c firmware/adaslice_fw.c
$(B)/bench-plan-mps2.elf: $(BENCH_PLAN_SRC) bench/mcu_profile.h $(FW_MPS2)/board.h $(FW_MPS2)/mps2.ld \
                          $(FW_CM3_HDRS) $(FW_HDRS)
	@mkdir -p $(B)
	$(ARM_CC) $(FW_ARM_FLAGS) -I$(FW_MPS2) -T $(FW_MPS2)/mps2.ld $(BENCH_PLAN_SRC) -o $@ $(FW_ARM_LIBS)

# The ATmega2560: board.h is force-included so that the core's row buffer
# (FW_ROW_BYTES) follows the board's display. The stack grows down from the
# end of SRAM to the end of .bss; stack.ld has the link fail unless
# FW_AVR_STACK bytes of it fit above the canary (ramps.c), as the Cortex-M3
# scripts do with STACK_SIZE. The reserve is the deepest the simavr tests
# measured (avr-run's stack_peak, from the canary up) and at least 128
# bytes more: tests/test_avr.c fails when a run goes deeper than the
# reserve less those 128.
AVR_CC   ?= avr-gcc
AVR_SIZE ?= avr-size
AVR_NM   ?= avr-nm
FW_RAMPS = firmware/ports/ramps
FW_RAMPS_SRC = $(FW_RAMPS)/main.c $(FW_RAMPS)/ramps.c $(FW_CORE_SRC)
FW_AVR_STACK = 640
FW_AVR_FLAGS = -mmcu=atmega2560 -Os -std=c99 -Wall -Wextra -Wpedantic -Werror -ffunction-sections -fdata-sections \
               -Wl,--gc-sections -I$(FW_RAMPS) -include $(FW_RAMPS)/board.h \
               -Wl,--defsym=__stack_reserve=$(FW_AVR_STACK) $(FW_RAMPS)/stack.ld
FW_AVR_RAM = 8192
FW_RAMPS_TEST = -DBOARD_DISPLAY_W=240u -DBOARD_DISPLAY_H=200u -DBOARD_PITCH_NM=100000u -DRAMPS_TEST_HANG -DRAMPS_TEST_OVERRUN
FW_RAMPS_DEPS = $(FW_RAMPS_SRC) $(FW_RAMPS)/board.h $(FW_RAMPS)/stack.ld $(FW_HDRS)

$(B)/fw-ramps.elf: $(FW_RAMPS_DEPS)
	@mkdir -p $(B)
	$(AVR_CC) $(FW_AVR_FLAGS) $(FW_RAMPS_SRC) -o $@

$(B)/fw-ramps-test.elf: $(FW_RAMPS_DEPS)
	@mkdir -p $(B)
	$(AVR_CC) $(FW_AVR_FLAGS) $(FW_RAMPS_TEST) $(FW_RAMPS_SRC) -o $@

# The RAMPS bench image (make bench: bench/bench_avr.c runs it under avr-run):
# motion.c's step computation and the planner, timed in cycles on the part.
$(B)/avr-bench.elf: bench/avr_bench.c bench/mcu_profile.h firmware/motion.c firmware/adaslice_fw.c $(FW_RAMPS)/board.h $(FW_RAMPS)/stack.ld $(FW_HDRS)
	@mkdir -p $(B)
	$(AVR_CC) $(FW_AVR_FLAGS) bench/avr_bench.c firmware/motion.c firmware/adaslice_fw.c -o $@

# flash = text + data (.data's image lives in flash), RAM = data + bss
# (.bss includes the stack on the Cortex-M3 images). On the ATmega2560
# data + bss counts .noinit and the stack's canary (up to stack.ld's
# __stack_low), the reserve is FW_AVR_STACK (the link refuses an image it
# does not fit) and what is left is free SRAM beyond it; the state
# BOARD_SAFETY places (ramps.c's tick, step and UV compare state, main.c's
# fw_state) must lie below the planner's workspace, the far end of SRAM
# from the stack.
FW_AVR_SAFETY = last_ticks step_when step_state uv_state uv_target uv_on_at uv_off_at uv_shift uv_level uv_want fw
FW_AVR_HEX = function hex(s,  v, i) { v = 0; for (i = 1; i <= length(s); i++) v = v * 16 + index("0123456789abcdef", substr(s, i, 1)) - 1; return v }

firmware: $(B)/fw-sim $(B)/fw-mps2.elf $(B)/fw-stm32f103.elf $(B)/fw-ramps.elf $(B)/fw-ramps-test.elf ramps-3840
	@for elf in $(B)/fw-mps2.elf $(B)/fw-stm32f103.elf; do \
	    $(ARM_SIZE) $$elf | awk -v elf=$$elf -v max=$(FW_RAM_MAX) 'NR == 2 { \
	        printf "%s: %d bytes of flash, %d bytes of RAM (of %d)\n", elf, $$1 + $$2, $$2 + $$3, max; \
	        if ($$2 + $$3 > max) { print elf ": over the RAM budget"; exit 1 } }' || exit 1; \
	done
	@for elf in $(B)/fw-ramps.elf $(B)/fw-ramps-test.elf; do \
	    flash=`$(AVR_SIZE) $$elf | awk 'NR == 2 { print $$1 + $$2 }'`; \
	    $(AVR_NM) -S $$elf | awk -v elf=$$elf -v ram=$(FW_AVR_RAM) -v flash=$$flash -v safety="$(FW_AVR_SAFETY)" \
	        '$(FW_AVR_HEX) \
	        { at[$$NF] = hex($$1); if (NF == 4) end[$$NF] = hex($$1) + hex($$2) } \
	        END { \
	            used = at["__stack_low"] - at["__data_start"]; reserve = at["__stack_reserve"]; \
	            if (!("__stack_low" in at) || !reserve) { print elf ": no stack reserve (stack.ld, FW_AVR_STACK)"; exit 1 } \
	            printf "%s: %d bytes of flash; SRAM: %d in data, bss and the stack canary, %d reserved for the stack, %d left (of %d)\n", \
	                elf, flash, used, reserve, ram - used - reserve, ram; \
	            n = split(safety, name, " "); top = 0; \
	            for (i = 1; i <= n; i++) { \
	                if (!(name[i] in end)) { print elf ": no symbol " name[i] " (FW_AVR_SAFETY)"; exit 1 } \
	                if (end[name[i]] > top) top = end[name[i]] } \
	            if (top > at["plan_workspace"]) { print elf ": the tick, step and UV state is not below the planner workspace"; exit 1 } \
	            printf "%s: the tick, step and UV state and fw_state end %d bytes below the stack'"'"'s room\n", \
	                elf, at["__stack_low"] - top }' || exit 1; \
	done

# The largest display the issue names, 3840 x 2400: its row buffer is 160
# bytes more than 2560's. The link either keeps the stack's reserve (then
# `firmware` prints the margin) or refuses, saying why; anything else fails.
.PHONY: ramps-3840
ramps-3840: $(FW_RAMPS_DEPS)
	@mkdir -p $(B)
	@if $(AVR_CC) $(FW_AVR_FLAGS) -DBOARD_DISPLAY_W=3840u -DBOARD_DISPLAY_H=2400u $(FW_RAMPS_SRC) -o $(B)/fw-ramps-3840.elf \
	        2> $(B)/fw-ramps-3840.log; then \
	    $(AVR_NM) $(B)/fw-ramps-3840.elf | awk -v ram=$(FW_AVR_RAM) '$(FW_AVR_HEX) { at[$$3] = hex($$1) } END { \
	        used = at["__stack_low"] - at["__data_start"]; reserve = at["__stack_reserve"]; \
	        if (!reserve || used + reserve > ram) { print "a 3840 x 2400 RAMPS image linked without its stack reserve"; exit 1 } \
	        printf "a 3840 x 2400 RAMPS image links: %d in data, bss and the canary, %d reserved for the stack, %d left\n", used, reserve, ram - used - reserve }'; \
	elif grep -q "ATmega2560 SRAM: data + bss" $(B)/fw-ramps-3840.log; then \
	    echo "a 3840 x 2400 RAMPS image is refused at link time:"; grep -o "ATmega2560 SRAM: .*" $(B)/fw-ramps-3840.log; \
	else \
	    cat $(B)/fw-ramps-3840.log; echo "a 3840 x 2400 RAMPS image failed to build"; exit 1; \
	fi
