"""The one parser of located addresses (plclab.iec.address) and the places that use it: the
image (runtime), the PSM layout (plants in OpenPLC) and CSV traces (a column named like an
address has its type). Bad addresses are one line that names them."""
from __future__ import annotations

import io

import pytest
from hypothesis import given
from hypothesis import strategies as st

from plclab.errors import PlcLabError
from plclab.iec.address import Address, AddressError, is_address, parse_address
from plclab.modbus.psm import parse_location
from plclab.runtime.image import image_slot
from plclab.trace.csvio import read_csv


def test_addresses_parse_to_area_and_index() -> None:
    assert parse_address("%IX1.6") == Address("I", "X", 1, 6)
    assert parse_address("%IX1.6").index == 14 and parse_address("%qw100").area == "QW"
    assert parse_address("%I0.1") == Address("I", "X", 0, 1)          # X is the default size
    assert parse_address("%MD7").bits == 32 and parse_address("%QB2").bits == 8
    assert parse_address("IX0.1", percent=False) == parse_address("%IX0.1")
    assert str(parse_address(" %ix3.2 ")) == "%IX3.2"


@pytest.mark.parametrize("bad, message", [
    ("IX0.1", "malformed address 'IX0.1'"),            # the % is required unless percent=False
    ("%IX1", "%IX1: a bit address is %IXbyte.bit with bit 0..7"),
    ("%IX1.8", "bit 0..7"),
    ("%QW3.1", "%QW3.1: a W address has no bit part"),
    ("%AX1.0", "malformed address"),
    ("", "malformed address"),
])
def test_a_malformed_address_is_one_line_naming_it(bad: str, message: str) -> None:
    with pytest.raises(AddressError) as e:
        parse_address(bad)
    assert message in str(e.value) and "\n" not in str(e.value)
    assert isinstance(e.value, PlcLabError) and isinstance(e.value, ValueError)
    assert not is_address(bad)


@given(st.sampled_from("IQM"), st.sampled_from("XBWDL"), st.integers(0, 5000), st.integers(0, 7))
def test_the_canonical_spelling_reads_back(prefix: str, size: str, number: int, bit: int) -> None:
    a = Address(prefix, size, number, bit if size == "X" else None)
    assert parse_address(str(a)) == a and parse_address(str(a).lower()) == a


def test_image_slots_are_openplc_areas_in_range() -> None:
    assert image_slot("%IX99.7") == ("IX", 799) and image_slot("%ML1023") == ("ML", 1023)
    assert image_slot("QX1.0", percent=False) == ("QX", 8)
    for bad, message in (("%IB0", "not an OpenPLC area"), ("%MX0.0", "not an OpenPLC area"),
                         ("%IX100.0", "byte 0..99, bit 0..7"), ("%QW1024", "a word address is %QW0..1023")):
        with pytest.raises(AddressError, match=message):
            image_slot(bad)


def test_psm_locations_are_the_psm_layout() -> None:
    assert parse_location("IX49.7") == ("IX", 399) and parse_location("%QW49") == ("QW", 49)
    with pytest.raises(ValueError, match="outside OpenPLC's PSM layout"):
        parse_location("MW0")


def test_a_csv_column_named_like_an_address_takes_its_type() -> None:
    text = "time_s,name,value\n0,%IX0.1,1\n0,%QW2,7\n0,%IW3.1,5\n0.5,%IX0.1,0\n"
    trace = read_csv(io.StringIO(text))
    assert trace.info("%IX0.1").kind == "bool" and trace.info("%QW2").width == 16
    assert trace.info("%IW3.1").width is None          # not an address: a plain int column
