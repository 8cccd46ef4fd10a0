/* fw-sim's figures that IDENTIFY states (fw_config's crc_byte_ns and
   plan_bin_ns): the pace of the simulator's loop, which runs on the host's
   own CPU beside the host tool and whatever else the machine runs. Its time
   is virtual (--speed), its work is not: a pass costs what the CPU takes,
   in wall time, as the host waits. A pass of 64 bytes of rows' CRC, or of 8
   bins planned, is a few microseconds of an idle core with the pty polled
   (the host's planner: docs/BENCHMARKS.md); the figures allow ten times
   that and more, since a process on a busy machine waits its turn for the
   CPU (the host's round-trip timer covers a wait once a frame, not once a
   pass). No test times them: a test may not depend on the machine's
   speed. */
#ifndef FW_SIM_BOARD_H
#define FW_SIM_BOARD_H
#define BOARD_CRC_BYTE_NS 1000u  /* 64 us a pass of 64 bytes */
#define BOARD_PLAN_BIN_NS 10000u /* 80 us a pass of 8 bins */
#endif
