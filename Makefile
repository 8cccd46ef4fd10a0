# adaslice: make | make demo | make check | make check-models | make bench
CC      ?= gcc
CLANG   ?= clang
CXX     ?= g++
CLANGXX ?= clang++
ARM_CC  ?= arm-none-eabi-gcc
WARN     = -Wall -Wextra -Wpedantic -Werror
CSTD     = -std=c99 $(WARN) -D_POSIX_C_SOURCE=200809L
CFLAGS  ?= -O2
SAN      = -O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
MODELS  ?= ../shared/models
FUZZ_SECONDS ?= 15
B        = build

FW_TEST_SRC = firmware/core.c firmware/motion.c firmware/gcode.c link/frame.c link/messages.c
HOST_SRC  = host/adaslice.c host/print.c host/serial.c link/tty.c link/frame.c link/messages.c host/svg.c host/slice.c host/orient.c host/printer.c host/png.c host/contour_svg.c \
            host/weights.c host/curvature.c host/saliency_cmd.c
TEST_SRC  = tests/run.c tests/test_planner.c tests/test_profiles.c tests/test_ldi.c tests/test_contours.c tests/test_masks.c tests/test_orient.c tests/test_png.c tests/test_loaders.c tests/test_cli.c host/png.c \
            tests/test_saliency.c tests/test_cli_weights.c tests/test_codec.c tests/test_link.c tests/test_motion.c tests/test_gcode.c \
            tests/test_firmware.c tests/test_print.c $(FW_TEST_SRC)
HDRS      = adaslice.h host/cli.h host/svg.h host/png.h host/printer.h host/contour_svg.h tests/check.h tests/meshgen.h tests/maskgen.h tests/failing_alloc.h \
            host/weights.h host/curvature.h host/serial.h link/tty.h link/frame.h link/messages.h tests/cli_run.h tests/zcheck.h tests/fakeport.h \
            firmware/fw.h firmware/motion.h firmware/gcode.h

include firmware/firmware.mk

.PHONY: all demo check check-models bench compile-checks fuzz clean

all: $(B)/adaslice

$(B):
	mkdir -p $(B)

$(B)/adaslice: $(HOST_SRC) $(HDRS) | $(B)
	$(CC) $(CSTD) $(CFLAGS) -pthread $(HOST_SRC) -o $@ -lm

# The main job on a bundled example: plan the hand (CC BY 4.0, see
# examples/models/README.md) scaled to the paper's 23.8 mm, plot it, and
# write its masks as a job for a 3840 x 2400 printer.
demo: $(B)/adaslice
	$(B)/adaslice plan examples/models/hand_closed.obj --scale 88.7 --compare \
	    --out $(B)/hand_plan.csv --plot $(B)/hand_plot.svg
	$(B)/adaslice slice examples/models/hand_closed.obj --scale 88.7 --printer photon-mono-4k -o $(B)/hand_job
	@echo "wrote $(B)/hand_plan.csv, $(B)/hand_plot.svg and the job $(B)/hand_job/"

# --- make check ----------------------------------------------------------
# Sanitized builds of the tool and the test runner; the runner prints the
# final "N passed, N failed".
$(B)/san/adaslice: $(HOST_SRC) $(HDRS) | $(B)
	mkdir -p $(B)/san
	$(CC) $(CSTD) $(SAN) -pthread $(HOST_SRC) -o $@ -lm

$(B)/san/run_tests: $(TEST_SRC) $(HDRS) | $(B)
	mkdir -p $(B)/san
	$(CC) $(CSTD) $(SAN) $(TEST_SRC) -o $@ -lm

# The header as C99 under gcc and clang, as C++ under g++ and clang++, two
# translation units linked together (plain and ADASLICE_STATIC), and the
# README's example.
compile-checks: | $(B)
	mkdir -p $(B)/cc
	$(CC) $(CSTD) -c tests/compile/one.c -o $(B)/cc/one_gcc.o
	$(CLANG) $(CSTD) -c tests/compile/one.c -o $(B)/cc/one_clang.o
	$(CXX) -x c++ -std=c++11 $(WARN) -c tests/compile/one.c -o $(B)/cc/one_gxx.o
	$(CLANGXX) -x c++ -std=c++11 $(WARN) -c tests/compile/one.c -o $(B)/cc/one_clangxx.o
	$(CC) $(CSTD) tests/compile/one.c tests/compile/two.c -o $(B)/cc/two_tu -lm
	$(CLANG) $(CSTD) -Wno-unused-function -DTWO_STATIC tests/compile/one.c tests/compile/two.c -o $(B)/cc/two_tu_static -lm
	$(CXX) -x c++ -std=c++11 $(WARN) tests/compile/one.c tests/compile/two.c -o $(B)/cc/two_tu_cxx -lm
	$(CC) $(CSTD) -DADASLICE_NO_STDIO -c tests/compile/one.c -o $(B)/cc/one_nostdio.o
	$(CC) $(CSTD) -O2 examples/plan_model.c -o $(B)/plan_model -lm
	$(CLANG) $(CSTD) -O2 examples/plan_model.c -o $(B)/cc/plan_model_clang -lm
	$(ARM_CC) -mcpu=cortex-m3 -mthumb -Os -std=c99 $(WARN) -Wno-unused-function -c tests/compile/mcu_planner.c \
	    -o $(B)/cc/mcu_planner.o
	arm-none-eabi-size $(B)/cc/mcu_planner.o | awk 'NR == 2 { print "integer planner on a Cortex-M3, N = 12000:", $$1, \
	    "bytes of code,", $$3, "bytes of RAM"; if ($$3 > 16384) exit 1 }'
	$(B)/cc/two_tu && $(B)/cc/two_tu_static && $(B)/cc/two_tu_cxx
	$(B)/plan_model examples/models/hand_closed.obj 88.7 > $(B)/cc/plan_model.out
	test "$$(wc -l < $(B)/cc/plan_model.out)" -eq 367
	sed -n '/^```c$$/,/^```$$/p' README.md | sed '1d;$$d' | diff - examples/plan_model.c
	@echo "compile checks: ok"

FUZZ = $(CLANG) -std=c99 $(WARN) -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all

$(B)/fuzz_loaders: tests/fuzz_loaders.c adaslice.h | $(B)
	$(FUZZ) tests/fuzz_loaders.c -o $@ -lm

$(B)/fuzz_gcode: tests/fuzz_gcode.c firmware/gcode.c firmware/motion.c $(FW_HDRS) | $(B)
	$(FUZZ) tests/fuzz_gcode.c firmware/gcode.c firmware/motion.c -o $@

$(B)/fuzz_firmware: tests/fuzz_firmware.c tests/fakeport.h tests/zcheck.h $(FW_CORE_SRC) $(FW_HDRS) | $(B)
	$(FUZZ) tests/fuzz_firmware.c $(FW_CORE_SRC) -o $@ -lm

# Bounded libFuzzer runs over the loaders, the G-code reader and the
# firmware's frames and messages; new inputs go to build/, not the repo.
fuzz: $(B)/fuzz_loaders $(B)/fuzz_gcode $(B)/fuzz_firmware
	@for t in loaders gcode firmware; do \
	    mkdir -p $(B)/fuzz_work/$$t; \
	    $(B)/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 -max_len=4096 \
	        -print_final_stats=1 $(B)/fuzz_work/$$t tests/fuzz_seeds/$$t > $(B)/fuzz_$$t.log 2>&1; \
	    status=$$?; echo "fuzz $$t:"; tail -n 12 $(B)/fuzz_$$t.log | grep -E "stat::number_of_executed_units|stat::peak_rss|ERROR|SUMMARY"; \
	    if [ $$status -ne 0 ]; then tail -n 40 $(B)/fuzz_$$t.log; exit $$status; fi; \
	done

$(B)/relay: tests/relay.c link/tty.c link/tty.h | $(B)
	$(CC) -std=c99 $(WARN) -O2 tests/relay.c link/tty.c -o $@

check: compile-checks firmware fuzz $(B)/san/adaslice $(B)/san/run_tests $(B)/fw-sim $(B)/relay
	ADASLICE_BIN=$(B)/san/adaslice $(B)/san/run_tests

# --- the shared models (not in the repository) ---------------------------
$(B)/test_models: tests/test_models.c adaslice.h tests/fakeport.h tests/zcheck.h $(FW_TEST_SRC) $(FW_HDRS) | $(B)
	$(CC) $(CSTD) $(SAN) tests/test_models.c $(FW_TEST_SRC) -o $@ -lm

check-models: $(B)/test_models
	$(B)/test_models $(MODELS)

# --- make bench -----------------------------------------------------------
$(B)/bench: bench/bench.c bench/timing.h host/png.c adaslice.h host/png.h | $(B)
	$(CC) $(CSTD) -O2 -march=x86-64-v2 bench/bench.c host/png.c -o $@ -lm

$(B)/bench_png: bench/bench_png.c bench/timing.h host/png.c host/png.h tests/maskgen.h adaslice.h | $(B)
	$(CC) $(CSTD) -O2 bench/bench_png.c host/png.c -o $@ -lm

$(B)/bench_saliency: bench/bench_saliency.c bench/timing.h adaslice.h | $(B)
	$(CC) $(CSTD) -O2 -march=x86-64-v2 bench/bench_saliency.c -o $@ -lm

ARM_NM ?= arm-none-eabi-nm
BENCH_PLAN_SRC = firmware/mps2/bench_plan.c firmware/mps2/board.c firmware/cm3/cm3.c firmware/adaslice_fw.c

$(B)/bench_wire: bench/bench_wire.c bench/timing.h adaslice.h | $(B)
	$(CC) $(CSTD) -O2 -march=x86-64-v2 bench/bench_wire.c -o $@ -lm

# The planner bench image: the mps2 board code and cm3 reset/tick with its
# own main, built as the firmware is (-Os, 20 KiB of RAM by mps2.ld).
$(B)/bench-plan-mps2.elf: $(BENCH_PLAN_SRC) bench/mcu_profile.h firmware/mps2/board.h firmware/mps2/mps2.ld \
                          $(FW_CM3_HDRS) $(FW_HDRS) | $(B)
	$(ARM_CC) $(FW_ARM_FLAGS) -T firmware/mps2/mps2.ld $(BENCH_PLAN_SRC) -o $@ $(FW_ARM_LIBS)

$(B)/bench_mcu_plan: bench/bench_mcu_plan.c bench/mcu_profile.h bench/timing.h adaslice.h | $(B)
	$(CC) $(CSTD) -O2 bench/bench_mcu_plan.c -o $@ -lm

bench: $(B)/bench $(B)/bench_png $(B)/bench_saliency $(B)/adaslice $(B)/bench_wire $(B)/bench_mcu_plan $(B)/bench-plan-mps2.elf
	$(B)/bench $(MODELS)
	$(B)/bench_png
	$(B)/bench_saliency $(MODELS)
	$(B)/bench_wire $(MODELS)
	$(B)/bench_mcu_plan $(B)/bench-plan-mps2.elf $(ARM_SIZE) $(ARM_NM)

clean:
	rm -rf $(B)
