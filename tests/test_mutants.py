"""Mutation operators (testing/mutants.py): the exact mutants of small
programs, one fault each, and the programs they apply to."""

from softplc_lite.app import load_app
from softplc_lite.ladder.fmt import format_rung
from softplc_lite.testing.mutants import mutants
from tests.helpers.apps import make_app

LADDER = (
    "BST XIC B3/0 NXB XIO B3/1 BND OTE B3/2\n"
    "XIC B3/3 OTL B3/4\n"
    "GRT N7:0 5 OTU B3/5\n"
    "XIC B3/6 TON T4:0 0.01 10 0\n"
    'CMP "N7:0 >= 3" JMP 7\n'
    "LBL 7 MOV 2 N7:1\n"
)


def _source(tmp_path, ladder=LADDER):
    app = load_app(make_app(tmp_path / "app", ladder), state_dir=tmp_path / "state", use_cache=False)
    return app.source_program, app.instructions


def test_each_operator_gives_its_mutants_in_program_order(tmp_path):
    source, instructions = _source(tmp_path)
    got = [(m.operator, m.key, m.pos.line, m.pos.column, m.description) for m in mutants(source, instructions)]
    assert got == [
        ("leg", (2, 0), 1, 5, "branch leg 1 of 2 removed: XIC B3/0"),
        ("leg", (2, 0), 1, 18, "branch leg 2 of 2 removed: XIO B3/1"),
        ("contact", (2, 0), 1, 5, "XIC B3/0 -> XIO B3/0"),
        ("contact", (2, 0), 1, 18, "XIO B3/1 -> XIC B3/1"),
        ("output", (2, 0), 1, 31, "OTE B3/2 removed"),
        ("rung", (2, 0), 1, 1, "rung deleted: BST XIC B3/0 NXB XIO B3/1 BND OTE B3/2"),
        ("contact", (2, 1), 2, 1, "XIC B3/3 -> XIO B3/3"),
        ("latch", (2, 1), 2, 10, "OTL B3/4 -> OTU B3/4"),
        ("rung", (2, 1), 2, 1, "rung deleted: XIC B3/3 OTL B3/4"),
        ("compare", (2, 2), 3, 1, "GRT N7:0 5 -> GEQ N7:0 5"),
        ("constant", (2, 2), 3, 1, "GRT N7:0 5 -> GRT N7:0 6"),
        ("constant", (2, 2), 3, 1, "GRT N7:0 5 -> GRT N7:0 4"),
        ("latch", (2, 2), 3, 12, "OTU B3/5 -> OTL B3/5"),
        ("rung", (2, 2), 3, 1, "rung deleted: GRT N7:0 5 OTU B3/5"),
        ("contact", (2, 3), 4, 1, "XIC B3/6 -> XIO B3/6"),
        # the preset, not the time base or the starting accumulator
        ("constant", (2, 3), 4, 10, "TON T4:0 0.01 10 0 -> TON T4:0 0.01 11 0"),
        ("constant", (2, 3), 4, 10, "TON T4:0 0.01 10 0 -> TON T4:0 0.01 9 0"),
        ("rung", (2, 3), 4, 1, "rung deleted: XIC B3/6 TON T4:0 0.01 10 0"),
        # an expression's comparison and constants; the label is left alone
        ("compare", (2, 4), 5, 1, 'CMP "N7:0 >= 3" -> CMP "N7:0 > 3"'),
        ("constant", (2, 4), 5, 1, 'CMP "N7:0 >= 3" -> CMP "N7:0 >= 4"'),
        ("constant", (2, 4), 5, 1, 'CMP "N7:0 >= 3" -> CMP "N7:0 >= 2"'),
        ("rung", (2, 4), 5, 1, 'rung deleted: CMP "N7:0 >= 3" JMP 7'),
        ("constant", (2, 5), 6, 7, "MOV 2 N7:1 -> MOV 3 N7:1"),
        ("constant", (2, 5), 6, 7, "MOV 2 N7:1 -> MOV 1 N7:1"),
        ("rung", (2, 5), 6, 1, "rung deleted: LBL 7 MOV 2 N7:1"),
    ]
    assert [m.index for m in mutants(source, instructions)] == list(range(len(got)))


def test_a_mutant_applies_its_one_change_and_leaves_the_original_alone(tmp_path):
    source, instructions = _source(tmp_path)
    before = [format_rung(r) for r in source.main.rungs]
    found = mutants(source, instructions)

    def rungs(m):
        return [format_rung(r) for r in m.apply(source).main.rungs]

    # a branch left with one leg is that leg in series
    assert rungs(found[0]) == ["XIO B3/1 OTE B3/2"] + before[1:]
    assert rungs(found[4]) == ["BST XIC B3/0 NXB XIO B3/1 BND"] + before[1:]
    assert rungs(found[5]) == before[1:]
    assert rungs(found[12]) == before[:2] + ["GRT N7:0 5 OTL B3/5"] + before[3:]
    assert [format_rung(r) for r in source.main.rungs] == before


def test_a_leg_of_three_removed_leaves_a_branch_and_nested_legs_mutate(tmp_path):
    ladder = "BST XIC B3/0 NXB BST XIC B3/1 NXB XIC B3/2 BND NXB XIC B3/3 BND OTE B3/4\n"
    source, instructions = _source(tmp_path, ladder)
    found = mutants(source, instructions)
    applied = {m.description: format_rung(m.apply(source).main.rungs[0]) for m in found if m.rung is not None}
    assert applied["branch leg 1 of 3 removed: XIC B3/0"] == \
        "BST BST XIC B3/1 NXB XIC B3/2 BND NXB XIC B3/3 BND OTE B3/4"
    assert applied["branch leg 1 of 2 removed: XIC B3/1"] == "BST XIC B3/0 NXB XIC B3/2 NXB XIC B3/3 BND OTE B3/4"
    assert applied["XIC B3/2 -> XIO B3/2"] == "BST XIC B3/0 NXB BST XIC B3/1 NXB XIO B3/2 BND NXB XIC B3/3 BND OTE B3/4"


def test_deleting_a_bare_sbr_or_a_final_bare_ret_is_no_mutant(tmp_path):
    """Either deletion leaves the program doing the same, so no scenario could catch it;
    a RET before the end of its file still is one (it skips the rungs after it)."""
    source, instructions = _source(tmp_path, "JSR 3\nFILE 3 Sub\nSBR\nRET\nADD N7:0 1 N7:0\nRET\n")
    deleted = [(m.key, m.description) for m in mutants(source, instructions) if m.operator == "rung"]
    assert deleted == [((2, 0), "rung deleted: JSR 3"), ((3, 1), "rung deleted: RET"),
                       ((3, 2), "rung deleted: ADD N7:0 1 N7:0")]
