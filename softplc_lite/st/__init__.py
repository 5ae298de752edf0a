"""Logix Structured Text: a routine's text parsed into a typed syntax tree.

The language is Rockwell's (1756-PM007, Logix 5000 Controllers Structured
Text): statements only, no declarations; ``:=`` and the non-retentive
``[:=]``; IF/ELSIF/ELSE, CASE with lists and ranges, FOR ... BY, WHILE,
REPEAT, EXIT, RETURN; instruction and Add-On Instruction calls as
statements; functions in expressions; Logix tags (members, ``.5`` bits,
``.[i]`` bits, arrays indexed by expressions, module tags ``Local:1:I``);
``//``, ``(* *)`` and ``/* */`` comments.

Our own grammar, not blark's (a choice, made after reading blark's
``iec.lark``): blark parses Beckhoff's TwinCAT dialect of IEC 61131-3 as
whole POUs (a PROGRAM or FUNCTION_BLOCK with its VAR sections), with the
Earley parser. A Logix routine is a bare statement list; its assignment
``[:=]``, its tag paths (``Local:1:I.Data.0``, ``Flags.5``, ``.[i]``),
``**``, ``/* */`` comments, empty instruction operands
(``GSV(WallClockTime, , LocalDateTime, d[0])``) and ``.5`` reals are not in
blark's grammar, while most of what is (declarations, pointers, methods,
``S=``/``R=``/``REF=``, pragmas, AND_THEN) is not Logix. Depending on blark
would mean patching its 950-line grammar and turning its tree into ours;
the Logix grammar is about 140 lines, runs with LALR (as the ladder grammar
does: linear time, and lark's interactive parser lets one parse report every
error), and shares the ladder's positions and error classes. What we took
from blark: the layering of expression rules by precedence, and
case-insensitive keywords that lark keeps apart from names.

- ``grammar.lark``: the grammar.
- ``ast``: the typed nodes, each with its place in the export.
- ``parser``: ``parse_routine`` and the located errors (``StError``).

Nothing here runs ST: checking it against the tags and compiling it are the
next stages'.
"""
