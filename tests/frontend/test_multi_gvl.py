"""Several stands checked together: each GVL file is a global scope of its own (two consoles
both have an SB1), each POU is checked against the GVL that declares its VAR_EXTERNALs."""
from __future__ import annotations

import pytest

from plclab.errors import CompileError, PlcLabError
from plclab.frontend import check_sources
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC

GVL_A = ("GVL_A.st", "VAR_GLOBAL\n    SB1 AT %IX1.6 : BOOL;\n    L1 AT %QX0.0 : BOOL;\nEND_VAR\n")
GVL_B = ("GVL_B.st", "VAR_GLOBAL\n    SB1 AT %IX1.3 : BOOL;\n    DRIVE1 AT %QW0 : INT;\nEND_VAR\n")
PRG_A = ("PRG_A.st", "PROGRAM PRG_A\nVAR_EXTERNAL\n    SB1 : BOOL;\n    L1 : BOOL;\nEND_VAR\nL1 := SB1;\nEND_PROGRAM\n")
PRG_B = ("PRG_B.st", "PROGRAM PRG_B\nVAR_EXTERNAL\n    SB1 : BOOL;\n    DRIVE1 : INT;\nEND_VAR\n"
                     "DRIVE1 := BOOL_TO_INT(SB1) * 500;\nEND_PROGRAM\n")


def test_two_stands_check_together_although_both_consoles_have_sb1():
    checked = check_sources([GVL_A, GVL_B, PRG_A, PRG_B])
    assert checked.scope_count == 2
    ext_b = next(d for d in checked.pous["PRG_B"].decls if d.key == "SB1")
    assert ext_b.global_decl.location.text == "%IX1.3"      # PRG_B got the GVL that has DRIVE1


def test_a_pou_whose_externals_no_gvl_declares_is_still_an_error():
    bad = ("PRG_C.st", "PROGRAM PRG_C\nVAR_EXTERNAL\n    L1 : BOOL;\n    DRIVE1 : INT;\nEND_VAR\n"
                       "L1 := DRIVE1 > 0;\nEND_PROGRAM\n")
    with pytest.raises(CompileError) as e:
        check_sources([GVL_A, GVL_B, bad])
    assert "has no matching VAR_GLOBAL" in str(e.value)


def test_a_duplicate_inside_one_gvl_file_is_still_an_error():
    dup = ("GVL_D.st", "VAR_GLOBAL\n    X : BOOL;\n    X : INT;\nEND_VAR\n")
    with pytest.raises(CompileError, match="GVL_D.st:3:5: error: 'X' is already declared"):
        check_sources([dup])


def test_the_runtime_refuses_to_run_several_stands_at_once():
    checked = check_sources([GVL_A, GVL_B, PRG_A, PRG_B])
    with pytest.raises(PlcLabError, match="several stands"):
        PLC(compile_unit(checked))
