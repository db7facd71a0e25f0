"""VCD output parsed back with pyvcd's own tokenizer: types, widths, names, times, values."""
from __future__ import annotations

import io

import pytest
from vcd.reader import TokenKind, tokenize

from plclab.trace import Trace, vcd_names, write_vcd

MS = 1_000_000


def parse(text: str):
    """-> (header dict, {dotted ref: VarDecl}, {dotted ref: [(time, value)]})."""
    header, decls, by_id, scope = {}, {}, {}, []
    history: dict[str, list] = {}
    now = 0
    for tok in tokenize(io.BytesIO(text.encode())):
        if tok.kind is TokenKind.SCOPE:
            scope.append(tok.data.ident)
        elif tok.kind is TokenKind.UPSCOPE:
            scope.pop()
        elif tok.kind is TokenKind.VAR:
            ref = ".".join([*scope, tok.data.reference])
            decls[ref] = tok.data
            by_id.setdefault(tok.data.id_code, []).append(ref)
        elif tok.kind in (TokenKind.COMMENT, TokenKind.TIMESCALE):
            header[tok.kind] = tok.data
        elif tok.kind is TokenKind.CHANGE_TIME:
            now = tok.data
        elif tok.kind.name.startswith("CHANGE_"):
            for ref in by_id[tok.data.id_code]:
                history.setdefault(ref, []).append((now, tok.data.value))
    return header, decls, history


def sample() -> Trace:
    t = Trace()
    t.declare("%QX1.0", "bool", False)
    t.declare("%IW3", "int", 0, width=16)
    t.declare("PRG_Main.fbPi.Y", "real", 0.0)
    t.declare("PRG_Main.state", "str", "IDLE")
    t.declare("PRG_Main.delta", "int", 0, width=8)
    t.alias("HL1", "%QX1.0")
    t.change(1_500 * MS, "%QX1.0", True)
    t.change(2 * MS, "%IW3", 27648)
    t.change(3 * MS, "PRG_Main.fbPi.Y", 12.5)
    t.change(4 * MS, "PRG_Main.state", "RUN 2")
    t.change(5 * MS, "PRG_Main.delta", -3)
    t.advance(2_000 * MS)
    return t


def test_variable_types_widths_and_scopes():
    buf = io.StringIO()
    mapping = write_vcd(sample(), buf)
    _header, decls, _h = parse(buf.getvalue())
    assert mapping["%QX1.0"] == "plc.io.QX1_0"
    got = {ref: (d.type_.value, d.size) for ref, d in decls.items()}
    assert got == {
        "plc.io.QX1_0": ("wire", 1),
        "plc.io.IW3": ("reg", 16),
        "plc.PRG_Main.fbPi.Y": ("real", 64),
        "plc.PRG_Main.state": ("string", 1),
        "plc.PRG_Main.delta": ("reg", 8),
        "plc.alias.HL1": ("wire", 1),
    }
    assert decls["plc.alias.HL1"].id_code == decls["plc.io.QX1_0"].id_code


def test_changes_at_ns_timestamps_with_twos_complement():
    buf = io.StringIO()
    write_vcd(sample(), buf)
    header, _d, hist = parse(buf.getvalue())
    assert header[TokenKind.TIMESCALE].magnitude == 1
    assert header[TokenKind.TIMESCALE].unit.value == "ns"
    assert hist["plc.io.QX1_0"] == [(0, "0"), (1_500_000_000, "1")]
    assert hist["plc.io.IW3"] == [(0, 0), (2_000_000, 27648)]
    assert hist["plc.PRG_Main.delta"] == [(0, 0), (5_000_000, 0b11111101)]
    assert hist["plc.PRG_Main.fbPi.Y"] == [(0, 0.0), (3_000_000, 12.5)]
    assert hist["plc.PRG_Main.state"] == [(0, "IDLE"), (4_000_000, r"RUN\x202")]
    assert buf.getvalue().rstrip().endswith("#2000000000")   # GTKWave shows the whole run


def test_original_names_are_kept_in_the_header_comment():
    buf = io.StringIO()
    write_vcd(sample(), buf)
    comment = parse(buf.getvalue())[0][TokenKind.COMMENT]
    assert "plc.io.QX1_0 = %QX1.0" in comment
    assert "plc.io.IW3 = %IW3" in comment
    assert "plc.alias.HL1 = %QX1.0" in comment
    assert "PRG_Main.state" not in comment          # unchanged names are not listed


def test_name_mapping_is_legal_and_collision_free():
    m = vcd_names(["%QX1.0", "%QX1_0", "PRG.arr[3]", "PRG.9lives", "x y"])
    assert m == {"%QX1.0": "plc.io.QX1_0", "%QX1_0": "plc.io.QX1_0_2",
                 "PRG.arr[3]": "plc.PRG.arr_3", "PRG.9lives": "plc.PRG._9lives",
                 "x y": "plc.x_y"}


def test_microsecond_timescale_and_file_output(tmp_path):
    path = tmp_path / "run.vcd"
    write_vcd(sample(), path, names=["%QX1.0"], timescale="1 us")
    header, decls, hist = parse(path.read_text())
    assert header[TokenKind.TIMESCALE].unit.value == "us"
    assert set(decls) == {"plc.io.QX1_0", "plc.alias.HL1"}
    assert hist["plc.io.QX1_0"] == [(0, "0"), (1_500_000, "1")]
    with pytest.raises(ValueError, match="timescale"):
        write_vcd(sample(), io.StringIO(), timescale="1 ms")


def test_integer_width_is_inferred_and_out_of_range_is_refused():
    t = Trace()
    t.declare("small", "int", 0)
    t.declare("neg", "int", 0)
    t.declare("big", "int", 0)
    t.declare("tight", "int", 0, width=4)
    t.change(1, "small", 200)
    t.change(1, "neg", -200)
    t.change(1, "big", 70000)
    buf = io.StringIO()
    write_vcd(t, buf)
    _h, decls, _c = parse(buf.getvalue())
    assert [decls[f"plc.{n}"].size for n in ("small", "neg", "big")] == [8, 16, 32]
    t.change(2, "tight", 16)
    with pytest.raises(ValueError, match="tight: value 16 does not fit in 4 bits"):
        write_vcd(t, io.StringIO())
