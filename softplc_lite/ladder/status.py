"""The status file (S2): PLC-5 layout where PLC-5 has one, softplc
additions in words PLC-5 leaves free. docs/engine.md has the table and
the sources."""

# PLC-5 layout
ARITH_FLAGS = 0  # S:0  bit 0 carry, 1 overflow, 2 zero, 3 sign
CARRY, OVERFLOW, ZERO, SIGN = 0, 1, 2, 3
PROCESSOR_STATUS = 1  # S:1
FIRST_PASS_BIT = 15  # S:1/15
# S:4: SLC 500's free-running clock, 10 ms per count (PLC-5's S:3..S:6 hold a DH+ table softplc has not)
FREE_RUNNING_CLOCK = 4
FREE_RUNNING_CLOCK_MS = 10
LAST_SCAN_MS = 8  # S:8
MAX_SCAN_MS = 9  # S:9
PLC5_MINOR_FAULT_BITS = 10  # S:10 PLC-5 minor fault word 1 (only its /14 arithmetic overflow is used)
MAJOR_FAULT_BITS = 11  # S:11
MAJOR_FAULT_CODE = 12  # S:12
FAULT_FILE = 13  # S:13 program file where the major fault happened
FAULT_RUNG = 14  # S:14 rung where it happened
MINOR_FAULT_BITS = 17  # S:17 PLC-5 minor fault word 2 (softplc assignments of its bits below)
INDEX_REGISTER = 24  # S:24
WATCHDOG_MS = 28  # S:28

# S:11 major fault word bits (PLC-5 meanings)
MAJOR_RUNTIME_BIT = 2  # "programming error" (run-time ladder error)
MAJOR_WATCHDOG_BIT = 8  # watchdog timeout

# S:10/14: PLC-5's arithmetic overflow minor fault (1785-6.5.14, processor status file appendix)
MINOR_OVERFLOW_BIT = 14  # math overflow (also S:0/1), in S:10

# S:17 minor fault bits (softplc assignments; /0 is left unused since overflow moved to S:10/14)
MINOR_DIV_ZERO_BIT = 1  # division by zero
MINOR_STRING_BIT = 2  # string instruction error (length, index)
MINOR_MODULE_BIT = 3  # a module (TLM) instruction without a CONTROL failed (STRPRINT)
MINOR_STORAGE_BIT = 4  # a retentive save or a --record trace write failed (cleared when one succeeds again)

# softplc additions (words 100..109)
SCAN_COUNT_LOW = 100  # S:100/S:101 scans since RUN, 32-bit, low word first
SCAN_COUNT_HIGH = 101
MINOR_FAULT_CODE = 102  # last minor fault code
MINOR_FAULT_FILE = 103
MINOR_FAULT_RUNG = 104
MODE_WORD = 105  # 0 PROGRAM, 1 RUN, 2 TEST, 3 FAULTED

DEFAULT_WATCHDOG_MS = 500

# Major fault codes (S:12), PLC-5 numbering where PLC-5 has the fault.
FAULT_INDIRECT_RANGE = 20  # indirect/indexed address outside its file
FAULT_INDIRECT_FILE = 24  # indirect file number names no file of that type
FAULT_JSR_NESTING = 30  # subroutines nested too deep
FAULT_NEGATIVE_TIMER = 34  # negative timer preset or accumulator
FAULT_WATCHDOG = 200  # softplc: scan longer than S:28
FAULT_DIV_ZERO = 201  # softplc: division by zero with divide_by_zero = "fault"
FAULT_BLOCK_RANGE = 202  # softplc: COP/FLL (or a module's) block past the end of its file
FAULT_MODULE_CONFIG = 203  # softplc: a module's configuration file failed to (re)load
FAULT_INTERNAL = 255  # softplc: an internal error (a bug), contained as a fault

# Minor fault codes (S:102)
MINOR_CODE_OVERFLOW = 1
MINOR_CODE_DIV_ZERO = 2
MINOR_CODE_STRING = 3
MINOR_CODE_FORMAT_INDEX = 4  # a format index with no string in the table
MINOR_CODE_FORMAT = 5  # an illegal format string (e.g. %k)
MINOR_CODE_PARAM = 6  # a Param missing, of the wrong kind, or past the end of its file
MINOR_CODE_PORT = 7  # a module instruction names a port that is not configured or is down
MINOR_CODE_OPERAND = 8  # a module instruction operand out of its range (e.g. a slave id past 247)
MINOR_CODE_SAVE = 9  # the retentive snapshot could not be saved (read-only directory, disk full)
MINOR_CODE_RECORD = 10  # a --record trace could not be written

# SLC 500's 32-bit math register is S:13 (low word) and S:14 (high word)
# (1747-RM001, math instructions); here S:13/S:14 keep PLC-5's fault file and
# rung, so the register lives in softplc words S:106 (low) and S:107 (high).
# DDV divides it and leaves its unrounded quotient (high) and remainder (low).
MATH_REGISTER_LOW = 106
MATH_REGISTER_HIGH = 107
