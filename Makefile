# adaslice
#   make               the tool, build/adaslice
#   make demo          plan, plot and slice a bundled model
#   make test          the unit and command-line tests: needs gcc only
#   make check         everything: compile checks (gcc, clang, g++, clang++, the
#                      ARM cross compiler), the firmware images, bounded fuzzing,
#                      and every test, those with real clients and emulators too
#   make check-models  tests over ../shared/models (MODELS=DIR for another place)
#   make bench         the benchmarks
#   make docs          docs/hybrid_path.svg, README's picture of the contour (needs prusa-slicer)
#   make firmware      the firmware images and their flash and RAM
# CC and CFLAGS are honoured (the warnings and the C standard are always on).

ifeq ($(origin CC),default)
CC = gcc
endif
ifeq ($(origin CXX),default)
CXX = g++
endif
CLANG   ?= clang
CLANGXX ?= clang++
ARM_CC  ?= arm-none-eabi-gcc
CFLAGS  ?= -O2
WARN     = -Wall -Wextra -Wpedantic -Werror
CSTD     = -std=c99 $(WARN) -D_POSIX_C_SOURCE=200809L
SAN      = -O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
BENCH_CFLAGS ?= -O2 -march=x86-64-v2
MODELS  ?= ../shared/models
FUZZ_SECONDS ?= 15
B        = build

.PHONY: all demo test check check-models bench firmware compile-checks fuzz clean run-groups docs FORCE

all: $(B)/adaslice

# ---- sources -------------------------------------------------------------
# host/library.c is the library's implementation (adaslice.h and
# adaslice_mcu.h): one object per configuration, linked by every program.
LIB_SRC   = host/library.c
LINK_SRC  = link/frame.c link/messages.c
HOST_SRC  = $(filter-out $(LIB_SRC),$(wildcard host/*.c host/*/*.c)) link/tty.c $(LINK_SRC)
FW_SRC    = firmware/core.c firmware/motion.c firmware/gcode.c $(LINK_SRC)
# The one list of test groups: tests/test_NAME.c defines test_NAME().
TESTS     = $(sort $(wildcard tests/test_*.c))
TEST_SRC  = tests/run.c $(TESTS) host/codec/png.c $(FW_SRC) $(LIB_SRC)
TEST_SRC += tests/job_readers.c $(filter-out host/main.c,$(HOST_SRC))

# Objects, built once per configuration: build/rel (the tool, CFLAGS),
# build/san (the tests, ASan + UBSan), build/bench (BENCH_CFLAGS), build/o3 and build/m32 (compile-checks).
objs = $(patsubst %.c,$(B)/$(1)/%.o,$(2))
$(B)/rel/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(CFLAGS) -pthread -MMD -MP -c $< -o $@
$(B)/san/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(SAN) -pthread -MMD -MP -c $< -o $@
$(B)/bench/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(BENCH_CFLAGS) -pthread -MMD -MP -c $< -o $@
$(B)/o3/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) -O3 -pthread -MMD -MP -c $< -o $@
$(B)/m32/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(CSTD) $(M32) -O2 -pthread -MMD -MP -c $< -o $@
-include $(shell find $(B) -name '*.d' 2>/dev/null)

$(B)/adaslice: $(call objs,rel,$(HOST_SRC) $(LIB_SRC))
	$(CC) $(CFLAGS) -pthread $^ -o $@ -lm

# The main job on a bundled example: the hand (CC BY 4.0, see
# examples/models/README.md) at the paper's scale (23.8 mm lying flat) stood
# on its wrist, fingers up (--orient 0,1,0: 83 mm tall), where its steep
# walls let layers thicken, unlike lying flat; planned against uniform layers
# of no larger worst error, plotted, and written as a job for a 3840 x 2400 printer.
demo: $(B)/adaslice
	$(B)/adaslice plan examples/models/hand_closed.obj --scale 88.7 --orient 0,1,0 --compare \
	    --out $(B)/hand_plan.csv --plot $(B)/hand_plot.svg
	$(B)/adaslice slice examples/models/hand_closed.obj --scale 88.7 --orient 0,1,0 --printer photon-mono-4k \
	    -o $(B)/hand_job
	@echo "wrote $(B)/hand_plan.csv, $(B)/hand_plot.svg and the job $(B)/hand_job/"

include firmware/firmware.mk

# ---- the tests -------------------------------------------------------------
# The runner's group table, made from TESTS; rewritten only when the list changes.
$(B)/test_groups.h: FORCE
	@mkdir -p $(B)
	@printf '%s\n' $(patsubst tests/test_%.c,'TEST_GROUP(%)',$(TESTS)) > $@.new
	@cmp -s $@.new $@ || mv $@.new $@; rm -f $@.new
$(B)/san/tests/run.o: $(B)/test_groups.h
$(B)/san/tests/run.o: CSTD += -I$(B)

$(B)/san/adaslice: $(call objs,san,$(HOST_SRC) $(LIB_SRC))
	$(CC) $(SAN) -pthread $^ -o $@ -lm
$(B)/san/run_tests: $(call objs,san,$(TEST_SRC))
	$(CC) $(SAN) -pthread $^ -o $@ -lm
$(B)/relay: $(call objs,rel,tests/relay.c link/tty.c)
	$(CC) $^ -o $@
# The ATmega2560 images under simavr (libsimavr-dev, libelf-dev)
$(B)/avr-run: $(call objs,rel,tests/avr_run.c link/tty.c)
	$(CC) $^ -o $@ -lsimavr -lelf

# What the test runner starts: the tool (sanitized), the firmware simulator
# and the faulty-line relay; make check adds the Cortex-M3 image for QEMU and
# the ATmega2560 images with their simavr harness.
TEST_PROGRAMS = $(B)/san/run_tests $(B)/san/adaslice $(B)/fw-sim $(B)/relay
RUN_TESTS     = ADASLICE_BIN=$(B)/san/adaslice $(B)/san/run_tests

# The groups run as parallel jobs, one log each in build/test-logs (a group's
# cases share its programs and files, so a group is the unit); the slowest,
# which wait on emulators and serial links, start first. tests/summary.sh adds
# the logs up and prints "N passed, N failed" last.
SLOW_GROUPS = avr print screen formats_zip contour outputs slice_jobs cli input_defects masks png hybrid orient threemf qemu_timing
GROUPS      = $(filter $(SLOW_GROUPS),$(patsubst tests/test_%.c,%,$(TESTS))) \
              $(filter-out $(SLOW_GROUPS),$(patsubst tests/test_%.c,%,$(TESTS)))
GROUP_LOGS  = $(patsubst %,$(B)/test-logs/%.log,$(GROUPS))
TEST_JOBS  ?= $(shell nproc 2>/dev/null || echo 2)
$(B)/test-logs/%.log: FORCE
	@mkdir -p $(@D)
	@start=$$(date +%s); $(RUN_TESTS) $(RUN_FLAGS) $* > $@.part 2>&1; \
	    echo "group $* ran $$(( $$(date +%s) - start )) s" >> $@.part; mv $@.part $@; echo "test group $* done"
run-groups: $(GROUP_LOGS)
define run_groups
	@rm -rf $(B)/test-logs
	@$(MAKE) --no-print-directory -j$(TEST_JOBS) run-groups RUN_FLAGS=$(1) || true
	@tests/summary.sh $(B)/test-logs $(words $(GROUPS))
endef

# gcc alone: cases that need a real client or an emulator are left to make
# check, and the runner names them.
test: $(TEST_PROGRAMS)
	$(call run_groups,--without-tools)

# The benchmarks are built (not run) too, so that make bench cannot stop linking unseen.
BENCH_PROGRAMS = $(B)/bench_plan $(B)/bench_png $(B)/bench_saliency $(B)/bench_wire $(B)/bench_mcu_plan $(B)/bench_jobs $(B)/bench_avr \
                 $(B)/bench_screen
check: compile-checks firmware fuzz $(TEST_PROGRAMS) $(B)/fw-mps2.elf $(B)/fw-mps2-busy.elf $(B)/fw-mps2-trace.elf $(B)/fw-mps2-hang.elf \
       $(B)/fw-ramps-test.elf $(B)/avr-run $(B)/avr-bench.elf $(BENCH_PROGRAMS)
	$(call run_groups,)

# The header as C99 under gcc and clang, as C++ under g++ and clang++, two
# translation units linked together (plain and ADASLICE_STATIC), every
# ADASLICE_NO_* switch, the README's example, and the integer planner for a
# Cortex-M3 (under 16 KiB of RAM for 12,000 bins).
NO_SWITCHES = LOADERS SAMPLED WEIGHTS ORIENT CONTOURS HYBRID STDIO
# The tool's sources at -O3 too: gcc's deeper inlining finds warnings -O2 does
# not (a packager's CFLAGS=-O3 must build under -Werror). And the tool as a
# 32-bit program (a printer's ARM Linux board): a size_t of 32 bits makes
# some range checks always false, which gcc warns of. SSE arithmetic, as the
# header's FLOATING POINT note asks on 32-bit x86.
M32 = -m32 -msse2 -mfpmath=sse -D_FILE_OFFSET_BITS=64
$(B)/cc/adaslice_m32: $(call objs,m32,$(HOST_SRC) $(LIB_SRC))
	@mkdir -p $(@D)
	$(CC) $(M32) -pthread $^ -o $@ -lm
compile-checks: $(call objs,o3,$(HOST_SRC) $(LIB_SRC)) $(B)/cc/adaslice_m32
	@mkdir -p $(B)/cc
	$(CC) $(CSTD) -c tests/compile/one.c -o $(B)/cc/one_gcc.o
	$(CLANG) $(CSTD) -c tests/compile/one.c -o $(B)/cc/one_clang.o
	$(CXX) -x c++ -std=c++11 $(WARN) -c tests/compile/one.c -o $(B)/cc/one_gxx.o
	$(CLANGXX) -x c++ -std=c++11 $(WARN) -c tests/compile/one.c -o $(B)/cc/one_clangxx.o
	$(CC) $(CSTD) tests/compile/one.c tests/compile/two.c -o $(B)/cc/two_tu -lm
	$(CLANG) $(CSTD) -Wno-unused-function -DTWO_STATIC tests/compile/one.c tests/compile/two.c -o $(B)/cc/two_tu_static -lm
	$(CXX) -x c++ -std=c++11 $(WARN) tests/compile/one.c tests/compile/two.c -o $(B)/cc/two_tu_cxx -lm
	for s in $(NO_SWITCHES); do $(CC) $(CSTD) -DADASLICE_NO_$$s -c tests/compile/one.c -o $(B)/cc/one_no.o || exit 1; done
	$(CLANG) $(CSTD) $(patsubst %,-DADASLICE_NO_%,$(NO_SWITCHES)) -c tests/compile/one.c -o $(B)/cc/one_no_all.o
	$(CXX) -x c++ -std=c++11 $(WARN) -c link/messages.c -o $(B)/cc/messages_cxx.o
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
	tests/check_reference.sh adaslice.h adaslice_mcu.h
	@# README's package list is the one .ci/run installs
	sed -n '/^for pkg in/,/; do/p' .ci/run | sed 's/for pkg in//; s/; do.*//; s/\\//g' | tr -s ' \n' '\n' | sed '/^$$/d' | sort \
	    > $(B)/cc/ci_packages
	sed -n '/apt-get install/,/^```/p' README.md | sed 's/.*apt-get install//; s/\\//g; /```/d' | tr -s ' \n' '\n' | sed '/^$$/d' \
	    | sort | diff $(B)/cc/ci_packages -
	@echo "compile checks: ok"

FUZZ = $(CLANG) -std=c99 $(WARN) -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all

$(B)/fuzz_loaders: tests/fuzz_loaders.c adaslice.h adaslice_mcu.h
	@mkdir -p $(B)
	$(FUZZ) tests/fuzz_loaders.c -o $@ -lm
$(B)/fuzz_gcode: tests/fuzz_gcode.c firmware/gcode.c firmware/motion.c $(FW_HDRS)
	@mkdir -p $(B)
	$(FUZZ) tests/fuzz_gcode.c firmware/gcode.c firmware/motion.c -o $@
$(B)/fuzz_contour: tests/fuzz_contour.c host/gcode.c host/gcode.h host/codec/inflate.c host/codec/inflate.h
	@mkdir -p $(B)
	$(FUZZ) tests/fuzz_contour.c host/gcode.c host/codec/inflate.c -o $@ -lm
$(B)/fuzz_firmware: tests/fuzz_firmware.c tests/fakeport.h tests/zcheck.h $(FW_CORE_SRC) $(FW_HDRS)
	@mkdir -p $(B)
	$(FUZZ) tests/fuzz_firmware.c $(FW_CORE_SRC) -o $@ -lm

# Bounded libFuzzer runs over the loaders, the firmware's G-code reader, the
# firmware's frames and messages, and contour's G-code and deflate readers;
# new inputs go to build/, not the repo.
fuzz: $(B)/fuzz_loaders $(B)/fuzz_gcode $(B)/fuzz_firmware $(B)/fuzz_contour
	@for t in loaders gcode firmware contour; do \
	    mkdir -p $(B)/fuzz_work/$$t; \
	    $(B)/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 -max_len=4096 \
	        -print_final_stats=1 $(B)/fuzz_work/$$t tests/fuzz_seeds/$$t > $(B)/fuzz_$$t.log 2>&1; \
	    status=$$?; echo "fuzz $$t:"; tail -n 12 $(B)/fuzz_$$t.log | grep -E "stat::number_of_executed_units|stat::peak_rss|ERROR|SUMMARY"; \
	    if [ $$status -ne 0 ]; then tail -n 40 $(B)/fuzz_$$t.log; exit $$status; fi; \
	done

# ---- the shared models (not in the repository) ---------------------------
$(B)/check_models: $(call objs,san,tests/check_models.c $(FW_SRC) $(LIB_SRC))
	$(CC) $(SAN) $^ -o $@ -lm

check-models: $(B)/check_models $(B)/adaslice
	@test -d $(MODELS) || { echo "make check-models: no model directory at $(MODELS): it holds the public meshes" \
	    "(shared/models beside this clone, outside the repository); give another place with MODELS=DIR"; exit 1; }
	ADASLICE_BIN=$(B)/adaslice $(B)/check_models $(MODELS)

# ---- make bench -----------------------------------------------------------
BENCH_LIB = $(call objs,bench,$(LIB_SRC))
$(B)/bench_plan: $(call objs,bench,bench/bench.c host/codec/png.c host/codec/deflate.c host/codec/maskrows.c host/bytes.c) $(BENCH_LIB)
	$(CC) $^ -o $@ -lm
$(B)/bench_png: $(call objs,bench,bench/bench_png.c host/codec/png.c host/codec/deflate.c host/codec/maskrows.c host/bytes.c) $(BENCH_LIB)
	$(CC) $^ -o $@ -lm
$(B)/bench_saliency: $(call objs,bench,bench/bench_saliency.c) $(BENCH_LIB)
	$(CC) $^ -o $@ -lm
$(B)/bench_wire: $(call objs,bench,bench/bench_wire.c $(LINK_SRC)) $(BENCH_LIB)
	$(CC) $^ -o $@ -lm
$(B)/bench_jobs: $(call objs,bench,bench/bench_jobs.c host/cure.c host/options.c host/report.c host/plan_job.c host/profile_csv.c host/model.c host/output.c host/pages.c \
                  host/search.c host/svg.c host/weights.c host/json.c) $(BENCH_LIB)
	$(CC) $^ -o $@ -lm
$(B)/bench_mcu_plan: $(call objs,bench,bench/bench_mcu_plan.c) $(BENCH_LIB)
	$(CC) $^ -o $@ -lm
$(B)/bench_screen: $(call objs,bench,bench/bench_screen.c host/print/screen.c host/options.c host/report.c $(LINK_SRC)) $(BENCH_LIB)
	$(CC) $^ -o $@ -lm
$(B)/bench_avr: $(call objs,bench,bench/bench_avr.c firmware/motion.c link/tty.c)
	$(CC) $^ -o $@ -lm

bench: $(BENCH_PROGRAMS) $(B)/adaslice $(B)/bench-plan-mps2.elf $(B)/fw-mps2-trace.elf $(B)/avr-run $(B)/avr-bench.elf \
       $(B)/fw-ramps-test.elf $(B)/fw-ramps.elf $(B)/san/run_tests
	$(B)/bench_plan $(MODELS)
	$(B)/bench_png
	$(B)/bench_screen
	$(B)/bench_saliency $(MODELS)
	$(B)/bench_jobs $(B)/adaslice $(MODELS)
	$(B)/bench_wire $(MODELS)
	$(B)/bench_mcu_plan $(B)/bench-plan-mps2.elf $(ARM_SIZE) $(ARM_NM)
	bench/qemu_timing.sh $(B)/fw-mps2-trace.elf $(B)/adaslice
	$(B)/bench_avr $(B)/avr-run $(B)/avr-bench.elf $(B)/fw-ramps-test.elf $(B)/fw-ramps.elf $(B)/adaslice $(AVR_SIZE)
	@echo "contoured surfaces (tests/test_contour.c on PrusaSlicer's G-code; needs prusa-slicer):"
	ADASLICE_BIN=$(B)/adaslice $(B)/san/run_tests contour

# README's picture of the contour (needs prusa-slicer): the shallow dome
# planned --hybrid, sliced by PrusaSlicer with the layer limits plan prints,
# and layer 46 (the top infill at 7.822 mm) drawn by contour --svg-path.
docs: $(B)/adaslice
	@mkdir -p $(B)/docs/prusa
	$(B)/adaslice plan examples/models/shallow_dome.obj --tmin 0.08 --tmax 0.28 --eps 0.1 --hybrid \
	    --3mf $(B)/docs/dome.3mf --out $(B)/docs/dome.csv > /dev/null
	prusa-slicer --datadir $(B)/docs/prusa --export-gcode --first-layer-height 0.28 --min-layer-height 0.08 \
	    --max-layer-height 0.28 --bed-shape 0x0,250x0,250x210,0x210 -o $(B)/docs/dome.gcode $(B)/docs/dome.3mf > /dev/null
	$(B)/adaslice contour $(B)/docs/dome.gcode --project $(B)/docs/dome.3mf -o $(B)/docs/dome-contoured.gcode \
	    --svg-path 46 docs/hybrid_path.svg

clean:
	rm -rf $(B)
