"""`plclab cnc PART.nc`: the per-frame table, the exit code, the output files; bad input is
one line and nothing runs."""
from __future__ import annotations

from plclab.cli import main


def test_cnc_runs_a_part_and_writes_the_tool_path(tmp_path, capsys):
    part = tmp_path / "part.nc"
    part.write_text("G21 G90 F600 M03\nG01 X1 Y0.5\nG02 X2 Y0 R0.6\n", encoding="utf-8")
    csv, svg, plot = tmp_path / "p.csv", tmp_path / "p.svg", tmp_path / "p.png"
    rc = main(["cnc", str(part), "--method", "dda", "--csv", str(csv), "--svg", str(svg), "--plot", str(plot)])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert "M words ignored" in out
    rows = [line for line in out.splitlines() if line.strip()[:1].isdigit()]
    assert len(rows) == 2 and " G01 " in rows[0] and " G02 " in rows[1]
    assert rows[0].endswith(" 600.0     593.6  ok")                # the start's fine cycle: within 2 %
    # the arc runs by digital integration: its ramps (V / A = 50 ms) on 1.4 mm are said
    assert rows[1].endswith("  in bound, BELOW THE FEED")
    assert "frame 2 reached 462 of F600 mm/min (77%): DDA runs an arc by digital integration" in out
    assert "ok: every frame within its bound; 1 of 2 frames below their programmed feed" in out
    lines = csv.read_text(encoding="utf-8").splitlines()
    assert lines[0] == "time_s,X,Y,Z,frame,feed_mm_min,reached_mm_min"
    assert lines[-1].split(",")[1:] == ["2.0000", "0.0000", "0.0000", "2", "600.0", "462.0"]
    assert svg.read_text(encoding="utf-8").startswith("<svg") and plot.read_bytes()[:4] == b"\x89PNG"


def test_cnc_bad_part_program_is_one_line_and_nothing_runs(tmp_path, capsys):
    part = tmp_path / "bad.nc"
    part.write_text("G01 X1 F100\nG01 X2 Y1 W3\n", encoding="utf-8")
    csv = tmp_path / "p.csv"
    rc = main(["cnc", str(part), "--csv", str(csv)])
    err = capsys.readouterr().err
    assert rc == 1
    assert err.strip() == f"{part}:2:11: error: unknown word 'W3' (supported: G00 G01 G02 G03 (I/J or R) " \
                          f"G17 G20 G21 G40 G41 G42 D G90 G91 F X Y Z N M02 M30; S T O and other M words ignored)"
    assert not csv.exists()


def test_cnc_block_beyond_the_travel_is_refused(tmp_path, capsys):
    part = tmp_path / "far.nc"
    part.write_text("G01 X200 F100\n", encoding="utf-8")
    assert main(["cnc", str(part)]) == 1
    assert "leaves the table's travel" in capsys.readouterr().err


def test_cnc_tool_table_from_the_command_line(tmp_path, capsys):
    part = tmp_path / "wall.nc"
    part.write_text("G21 G90 F600\nG41 D2 G01 X1 Y0\nX2\nY1\nG40 X3 Y2\n", encoding="utf-8")
    assert main(["cnc", str(part), "--tool", "D2=0.25"]) == 0
    out = capsys.readouterr().out
    assert "equidistant at 0.2500 / 0.2500 mm, tool radius 0.25 mm  ok" in out
    assert main(["cnc", str(part)]) == 1
    assert capsys.readouterr().err.strip().startswith(f"{part}:2:5: error: D2 is not in the tool table")


def test_cnc_arc_end_tolerance_is_the_step_given(tmp_path, capsys):
    """`--step` is the arc end's tolerance: 5 um off the circle is refused at a 1 um step,
    before anything runs."""
    part = tmp_path / "arc.nc"
    part.write_text("G01 X10 Y0 F100\nG03 X0 Y10.005 I-10 J0\n", encoding="utf-8")
    csv = tmp_path / "p.csv"
    assert main(["cnc", str(part), "--step", "0.001", "--csv", str(csv)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"{part}:2:5: error: the end point is not on the arc's circle") and \
        "tolerance one step, 0.001 mm" in err and err.count("\n") == 1
    assert not csv.exists()
