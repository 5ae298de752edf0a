"""Random Structured Text routines (hypothesis strategies) over a fixed set
of tags, for the executor differential test: typed expressions (integers,
REALs, BOOLs) with every operator and function of logix/st_expr.py, and
statements of every kind, calls of the function-block instructions (TONR
... OSFI) on their own tags, loops bounded so that a routine ends (a loop
that would not is another test's: the watchdog's)."""

from __future__ import annotations

from hypothesis import strategies as st

INTS = ("a", "b", "c", "w", "s")  # DINT, DINT, DINT, INT, SINT
REALS = ("x", "y")
BOOLS = ("p", "q", "Flags.3", "w.0")
TAGS = [("a", "DINT"), ("b", "DINT"), ("c", "DINT"), ("w", "INT"), ("s", "SINT"), ("x", "REAL"), ("y", "REAL"),
        ("p", "BOOL"), ("q", "BOOL"), ("Flags", "DINT"), ("arr", "DINT[4]")] + \
    [(f"{v}{d}", "DINT") for v in "kg" for d in (1, 2)] + \
    [("Tm", "FBD_TIMER"), ("Cn", "FBD_COUNTER"), ("Os", "FBD_ONESHOT")]  # the function-block instructions'
INITIAL = [name for name, t in TAGS if name not in ("arr",) and not t.startswith("FBD_")]

small_ints = st.integers(-20, 20)


def _int_leaf():
    return st.one_of(small_ints.map(str), st.sampled_from(INTS),
                     st.sampled_from(["arr[a AND 3]", "arr[(b AND 3)]", "16#1F", "2#101"]))


def int_expr(depth: int = 2):
    if depth == 0:
        return _int_leaf()
    sub = int_expr(depth - 1)
    return st.one_of(
        _int_leaf(),
        st.tuples(sub, st.sampled_from(["+", "-", "*", "/", "MOD", "AND", "OR", "XOR"]), sub).map(
            lambda t: f"({t[0]} {t[1]} {t[2]})"),
        sub.map(lambda e: f"-({e})"),
        sub.map(lambda e: f"ABS({e})"),
        sub.map(lambda e: f"NOT ({e})"),
    )


def real_expr(depth: int = 2):
    leaf = st.one_of(st.sampled_from(REALS), st.sampled_from(["1.5", "0.25", "-3.0", "2.0E1"]))
    if depth == 0:
        return leaf
    sub = real_expr(depth - 1)
    mixed = st.one_of(sub, int_expr(0))
    return st.one_of(
        leaf,
        st.tuples(sub, st.sampled_from(["+", "-", "*", "/"]), mixed).map(lambda t: f"({t[0]} {t[1]} {t[2]})"),
        st.tuples(st.sampled_from(["SIN", "COS", "ABS", "TRUNC", "SQRT", "LN", "ATAN"]), sub).map(
            lambda t: f"{t[0]}({t[1]})"),
        st.tuples(sub, small_ints.filter(lambda n: -3 <= n <= 3)).map(lambda t: f"({t[0]} ** {t[1]})"),
    )


def bool_expr(depth: int = 2):
    leaf = st.one_of(st.sampled_from(BOOLS), st.sampled_from(["TRUE", "FALSE"]),
                     st.tuples(int_expr(1), st.sampled_from(["<", "<=", ">", ">=", "=", "<>"]), int_expr(1)).map(
                         lambda t: f"({t[0]} {t[1]} {t[2]})"),
                     st.tuples(real_expr(0), st.sampled_from(["<", ">"]), real_expr(0)).map(
                         lambda t: f"({t[0]} {t[1]} {t[2]})"))
    if depth == 0:
        return leaf
    sub = bool_expr(depth - 1)
    return st.one_of(
        leaf,
        st.tuples(sub, st.sampled_from(["AND", "&", "OR", "XOR"]), sub).map(lambda t: f"({t[0]} {t[1]} {t[2]})"),
        sub.map(lambda e: f"NOT {e}"),
    )


def assignment():
    return st.one_of(
        st.tuples(st.sampled_from(INTS + ("arr[c AND 3]",)), int_expr()).map(lambda t: f"{t[0]} := {t[1]};"),
        st.tuples(st.sampled_from(INTS + REALS), real_expr()).map(lambda t: f"{t[0]} := {t[1]};"),
        st.tuples(st.sampled_from(BOOLS), bool_expr()).map(lambda t: f"{t[0]} := {t[1]};"),
        st.tuples(st.sampled_from(("p", "q")), bool_expr(1)).map(lambda t: f"{t[0]} [:=] {t[1]};"),
    )


def fbd_call():
    """A function-block instruction's inputs set, then its call (its
    outputs are read by later statements as any BOOL or DINT)."""
    return st.one_of(
        st.tuples(bool_expr(1), bool_expr(0), int_expr(1), st.sampled_from(["TONR", "TOFR", "RTOR"])).map(
            lambda t: f"Tm.TimerEnable := {t[0]};\nTm.Reset := {t[1]};\nTm.PRE := {t[2]};\n{t[3]}(Tm);\n"
                      f"p := Tm.DN XOR Tm.TT;\nc := c + Tm.ACC;"),
        st.tuples(bool_expr(1), bool_expr(1), bool_expr(0), int_expr(0)).map(
            lambda t: f"Cn.CUEnable := {t[0]};\nCn.CDEnable := {t[1]};\nCn.Reset := {t[2]};\nCn.PRE := {t[3]};\n"
                      f"CTUD(Cn);\nq := Cn.DN OR Cn.OV;\nc := c + Cn.ACC;"),
        st.tuples(bool_expr(1), st.sampled_from(["OSRI", "OSFI"])).map(
            lambda t: f"Os.InputBit := {t[0]};\n{t[1]}(Os);\nIF Os.OutputBit THEN a := a + 1; END_IF;"),
    )


def statements(depth: int = 2):
    if depth == 0:
        return st.lists(assignment(), min_size=1, max_size=3).map("\n".join)
    body = statements(depth - 1)
    return st.lists(st.one_of(
        assignment(),
        fbd_call(),
        st.tuples(bool_expr(), body, st.lists(st.tuples(bool_expr(1), body), max_size=2),
                  st.one_of(st.none(), body)).map(_if),
        st.tuples(int_expr(1), st.lists(st.tuples(st.lists(small_ints, min_size=1, max_size=2), body), min_size=1,
                                        max_size=3), st.one_of(st.none(), body)).map(_case),
        st.tuples(small_ints, small_ints, st.sampled_from([1, 2, -1, -3]), body, bool_expr(1),
                  st.just(depth)).map(_for),
        st.tuples(st.integers(0, 5), body, st.just(depth)).map(_while),
        st.tuples(st.integers(1, 4), body, st.just(depth)).map(_repeat),
    ), min_size=1, max_size=4).map("\n".join)


def _if(t):
    cond, body, elsifs, else_ = t
    out = f"IF {cond} THEN\n{body}\n"
    for c, b in elsifs:
        out += f"ELSIF {c} THEN\n{b}\n"
    if else_ is not None:
        out += f"ELSE\n{else_}\n"
    return out + "END_IF;"


def _case(t):
    selector, arms, else_ = t
    out, seen = f"CASE {selector} OF\n", set()
    for labels, body in arms:
        labels = [n for n in labels if n not in seen]
        if not labels:
            continue
        seen.update(labels)
        out += ", ".join(str(n) for n in labels) + f":\n{body}\n"
    if len(out.splitlines()) == 1:
        out += "0: a := a;\n"
    if else_ is not None:
        out += f"ELSE\n{else_}\n"
    return out + "END_CASE;"


def _for(t):
    start, stop, step, body, leave, depth = t
    # k<depth> is the count; nothing else writes it
    return f"FOR k{depth} := {start} TO {stop} BY {step} DO\n{body}\nIF {leave} THEN EXIT; END_IF;\nEND_FOR;"


def _while(t):
    times, body, depth = t
    return f"g{depth} := 0;\nWHILE g{depth} < {times} DO\ng{depth} := g{depth} + 1;\n{body}\nEND_WHILE;"


def _repeat(t):
    times, body, depth = t
    return f"g{depth} := 0;\nREPEAT\ng{depth} := g{depth} + 1;\n{body}\nUNTIL g{depth} >= {times} END_REPEAT;"


routines = statements()
