"""Real Allen-Bradley ladder mnemonics, for the unknown-instruction message.

An engineer porting a program who writes ``BTR`` should read "BTR is a
PLC-5 instruction softplc_lite does not implement", not "did you mean
BTD?". ``InstructionSet.hint`` asks ``ab_instruction`` only for names not
in its live table, so a mnemonic listed here that another group implements
is never called unimplemented.

Which families a mnemonic is in: the instruction lists of the PLC-5
Instruction Set Reference (1785-6.1), the SLC 500 Instruction Set Reference
(1747-RM001), the MicroLogix references (1762-RM001, 1763-RM001) and
Logix5000 General Instructions (1756-RM003). A family is
marked only where we are sure of it; the message names the families marked.
Motion, function-block-only and structured-text-only instructions are left
out (they do not appear in ladder text exports of these processors).
"""

from __future__ import annotations

P5, SLC, LGX, ML = "PLC-5", "SLC 500", "Logix5000", "MicroLogix"

# mnemonic -> (title, families)
AB_MNEMONICS: dict[str, tuple[str, tuple[str, ...]]] = {
    # bit, timer, counter
    **{m: (t, (P5, SLC, LGX)) for m, t in (
        ("XIC", "examine if closed"), ("XIO", "examine if open"), ("OTE", "output energize"),
        ("OTL", "output latch"), ("OTU", "output unlatch"), ("OSR", "one shot rising"),
        ("TON", "timer on delay"), ("TOF", "timer off delay"), ("RTO", "retentive timer on"),
        ("CTU", "count up"), ("CTD", "count down"), ("RES", "reset"))},
    "ONS": ("one shot", (P5, LGX)),
    "OSF": ("one shot falling", (P5, LGX)),
    "CTUD": ("count up/down", (LGX,)),
    "HSC": ("high-speed counter", (SLC,)),
    "RHC": ("read high-speed clock", (ML,)),
    "TDF": ("compute time difference", (ML,)),
    # compare
    **{m: (t, (P5, SLC, LGX)) for m, t in (
        ("EQU", "equal"), ("NEQ", "not equal"), ("LES", "less than"), ("LEQ", "less than or equal"),
        ("GRT", "greater than"), ("GEQ", "greater than or equal"), ("LIM", "limit test"),
        ("MEQ", "masked comparison for equal"))},
    "CMP": ("compare", (P5, LGX)),
    # math and conversion
    **{m: (t, (P5, SLC, LGX)) for m, t in (
        ("ADD", "add"), ("SUB", "subtract"), ("MUL", "multiply"), ("DIV", "divide"),
        ("NEG", "negate"), ("SQR", "square root"), ("CLR", "clear"), ("TOD", "convert to BCD"),
        ("FRD", "convert from BCD"), ("AND", "bitwise and"), ("OR", "bitwise inclusive or"),
        ("XOR", "bitwise exclusive or"), ("NOT", "bitwise not"), ("MOV", "move"), ("MVM", "masked move"),
        ("COP", "file copy"), ("FLL", "file fill"), ("CPT", "compute"), ("XPY", "x to the power of y"),
        ("SIN", "sine"), ("COS", "cosine"), ("TAN", "tangent"), ("ASN", "arc sine"), ("ACS", "arc cosine"),
        ("ATN", "arc tangent"), ("LN", "natural log"), ("LOG", "log to the base 10"))},
    "DDV": ("double divide", (SLC,)),
    "ABS": ("absolute value", (SLC, LGX)),
    "MOD": ("modulo", (SLC, LGX)),
    "DEG": ("radians to degrees", (SLC, LGX)),
    "RAD": ("degrees to radians", (SLC, LGX)),
    "SCL": ("scale", (SLC,)),
    "SCP": ("scale with parameters", (SLC,)),
    "SWP": ("swap", (SLC,)),
    "SWPB": ("swap byte", (LGX,)),
    "DCD": ("decode 4 to 1-of-16", (SLC,)),
    "ENC": ("encode 1-of-16 to 4", (SLC,)),
    "TRN": ("truncate", (LGX,)),
    "BTD": ("bit field distribute", (P5, LGX)),
    "BTDT": ("bit field distribute with target", (LGX,)),
    # file, shift, sequencer
    **{m: (t, (P5, SLC, LGX)) for m, t in (
        ("BSL", "bit shift left"), ("BSR", "bit shift right"), ("FFL", "FIFO load"), ("FFU", "FIFO unload"),
        ("LFL", "LIFO load"), ("LFU", "LIFO unload"), ("SQO", "sequencer output"), ("SQL", "sequencer load"))},
    "SQI": ("sequencer input", (P5, LGX)),
    "SQC": ("sequencer compare", (SLC,)),
    "FAL": ("file arithmetic and logic", (P5, LGX)),
    "FSC": ("file search and compare", (P5, LGX)),
    "AVE": ("file average", (P5, LGX)),
    "STD": ("file standard deviation", (P5, LGX)),
    "SRT": ("file sort", (P5, LGX)),
    "CPS": ("synchronous copy file", (LGX,)),
    "SIZE": ("size in elements", (LGX,)),
    "DDT": ("diagnostic detect", (P5, LGX)),
    "FBC": ("file bit comparison", (P5, LGX)),
    "DTR": ("data transitional", (P5, LGX)),
    # program control
    **{m: (t, (P5, SLC, LGX)) for m, t in (
        ("JMP", "jump to label"), ("LBL", "label"), ("JSR", "jump to subroutine"), ("SBR", "subroutine"),
        ("RET", "return"), ("MCR", "master control reset"), ("TND", "temporary end"))},
    "AFI": ("always false", (P5, LGX)),
    "NOP": ("no operation", (LGX,)),
    "EOT": ("end of transition", (P5, LGX)),
    "SFR": ("SFC reset", (P5, LGX)),
    "SFP": ("SFC pause", (LGX,)),
    "UID": ("user interrupt disable", (SLC, LGX)),
    "UIE": ("user interrupt enable", (SLC, LGX)),
    "UIF": ("user interrupt flush", (SLC,)),
    "SUS": ("suspend", (SLC,)),
    "STS": ("selectable timed start", (SLC,)),
    "STE": ("selectable timed enable", (SLC,)),
    "INT": ("interrupt subroutine", (SLC,)),
    "JXR": ("jump to external routine", (LGX,)),
    "FOR": ("for loop", (P5, LGX)),
    "NXT": ("next, the end of a FOR loop", (P5,)),
    "BRK": ("break", (P5, LGX)),
    "EVENT": ("trigger event task", (LGX,)),
    # I/O and communication
    "BTR": ("block transfer read", (P5,)),
    "BTW": ("block transfer write", (P5,)),
    "CIO": ("ControlNet I/O transfer", (P5,)),
    "IIN": ("immediate input", (P5,)),
    "IOT": ("immediate output", (P5, LGX)),
    "IDI": ("immediate data input", (P5,)),
    "IDO": ("immediate data output", (P5,)),
    "IIM": ("immediate input with mask", (SLC,)),
    "IOM": ("immediate output with mask", (SLC,)),
    "REF": ("I/O refresh", (SLC,)),
    "SVC": ("service communications", (SLC,)),
    "MSG": ("message", (P5, SLC, LGX)),
    "GSV": ("get system value", (LGX,)),
    "SSV": ("set system value", (LGX,)),
    "PID": ("proportional integral derivative", (P5, SLC, LGX)),
    # ASCII and strings
    **{m: (t, (P5, SLC, LGX)) for m, t in (
        ("ABL", "ASCII test for line"), ("ACB", "ASCII characters in buffer"), ("AHL", "ASCII handshake lines"),
        ("ARD", "ASCII read characters"), ("ARL", "ASCII read line"), ("AWA", "ASCII write append"),
        ("AWT", "ASCII write"))},
    **{m: (t, (P5, SLC)) for m, t in (
        ("ACI", "string to integer"), ("AIC", "integer to string"), ("ACN", "string concatenate"),
        ("AEX", "string extract"), ("ASC", "string search"), ("ASR", "ASCII string compare"))},
    "ACL": ("ASCII clear buffers", (SLC, LGX)),
    **{m: (t, (LGX,)) for m, t in (
        ("CONCAT", "string concatenate"), ("DELETE", "string delete"), ("FIND", "find string"),
        ("INSERT", "insert string"), ("MID", "middle string"), ("STOD", "string to DINT"),
        ("STOR", "string to REAL"), ("DTOS", "DINT to string"), ("RTOS", "REAL to string"),
        ("UPPER", "upper case"), ("LOWER", "lower case"))},
}


def ab_instruction(name: str) -> str | None:
    """``BTR (block transfer read) is a PLC-5 instruction`` for a real AB
    mnemonic, else None. The caller adds what softplc_lite does about it."""
    found = AB_MNEMONICS.get(name.upper())
    if found is None:
        return None
    title, families = found
    where = " and ".join(families) if len(families) < 3 else f"{families[0]}, {families[1]} and {families[2]}"
    article = "an" if where.startswith("SLC") else "a"
    return f"{name.upper()} ({title}) is {article} {where} instruction"
