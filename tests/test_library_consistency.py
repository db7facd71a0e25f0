"""What the checker accepts, the runtime can run: every standard function and function block
the front end knows has an implementation in the runtime's library."""
from __future__ import annotations

import pytest

from plclab.frontend import check_sources
from plclab.frontend.stdsigs import FUNCTION_BLOCKS, FUNCTIONS
from plclab.runtime.compiler import compile_unit
from plclab.runtime.plc import PLC
from plclab.iec import types as T
from plclab.runtime import stdfb, stdlib

PICK = {"ANY": "INT", "ANY_ELEMENTARY": "INT", "ANY_MAGNITUDE": "INT", "ANY_NUM": "INT", "ANY_INT": "INT",
        "ANY_REAL": "REAL", "ANY_BIT": "WORD", "ANY_NBIT": "WORD", "ANY_STRING": "STRING", "ANY_DATE": "DATE"}


def concrete(name: str) -> T.Type:
    return T.ELEMENTARY[PICK.get(name, name)]


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_every_function_the_checker_accepts_has_a_runtime_implementation(name):
    sig = FUNCTIONS[name]
    generic = next((g for p, g in sig.params if p in sig.generic_params), None)
    args = [concrete(g) for _p, g in sig.params]
    if sig.result == "T":
        result = concrete(generic) if generic else args[0]
    elif sig.result in T.ELEMENTARY:
        result = T.ELEMENTARY[sig.result]
    else:                                   # a result type chosen by the call's context
        result = concrete(sig.result)
    fn = stdlib.lookup(name, args, result)
    assert callable(fn)


@pytest.mark.parametrize("name", sorted(FUNCTION_BLOCKS))
def test_every_standard_function_block_exists_with_the_checked_interface(name):
    cls = getattr(stdfb, name)
    inst = cls(stdfb.ScanClock())
    sig = FUNCTION_BLOCKS[name]
    for var, _type in sig.inputs + sig.outputs:
        assert hasattr(inst, var), f"{name}.{var}"


INTS = ["BOOL", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "BYTE", "WORD", "DWORD", "LWORD"]
SAMPLES = {"BOOL": ["TRUE", "FALSE"], "SINT": ["-128", "127", "-1"], "INT": ["-32768", "32767", "-1", "300"],
           "DINT": ["-2147483648", "2147483647", "-1", "70000"], "LINT": ["-1", "5000000000"],
           "USINT": ["255", "0"], "UINT": ["65535", "40000"], "UDINT": ["4294967295", "3000000000"],
           "ULINT": ["18446744073709551615", "7"], "BYTE": ["16#FF", "16#80"], "WORD": ["16#FFFF", "16#8000"],
           "DWORD": ["16#FFFFFFFF"], "LWORD": ["16#FFFFFFFFFFFFFFFF"]}


@pytest.mark.parametrize("src", INTS)
def test_conversions_compiled_inline_give_what_the_library_gives(src):
    """The compiler inlines exact conversions for speed; every one must agree with the library."""
    pairs = [dst for dst in INTS if dst != src and f"{src}_TO_{dst}" in FUNCTIONS]
    decls = "\n".join(f"    y_{dst} : {dst};" for dst in pairs)
    for literal in SAMPLES[src]:
        body = "\n".join(f"y_{dst} := {src}_TO_{dst}(x);" for dst in pairs)
        src_text = f"PROGRAM prg\nVAR\n    x : {src} := {literal};\n{decls}\nEND_VAR\n{body}\nEND_PROGRAM\n"
        plc = PLC(compile_unit(check_sources([("conv.st", src_text)])))
        plc.scan()
        x = plc.read("prg.x")
        for dst in pairs:
            expected = stdlib.lookup(f"{src}_TO_{dst}", [T.ELEMENTARY[src]], T.ELEMENTARY[dst])(x)
            assert plc.read(f"prg.y_{dst}") == expected, f"{src}_TO_{dst}({x})"


def test_bcd_conversions_encode_and_decode():
    src = """PROGRAM prg
VAR u : USINT := 42; b : BYTE; w : WORD; back : UINT; END_VAR
b := USINT_TO_BCD(u);
w := UINT_TO_BCD(UINT#1234);
back := BCD_TO_UINT(w);
END_PROGRAM
"""
    plc = PLC(compile_unit(check_sources([("bcd.st", src)])))
    plc.scan()
    assert plc.read("prg.b") == 0x42 and plc.read("prg.w") == 0x1234 and plc.read("prg.back") == 1234
