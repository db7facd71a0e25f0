"""Modbus TCP framing and PDU codec (Modbus Application Protocol v1.1b3), written with struct.

Why not pymodbus's server: the Twido contract needs exact exception codes (02 for an address,
03 for a refused value, nothing written on either), writes must be validated whole before they
are queued to the process image, and a hostile frame must cost one closed connection at most.
pymodbus's datastore layer turns every refusal into 02 and its 3.x datastore addresses are
1-based, so a ~150 line codec that we own is simpler to reason about than adapting it.
pymodbus's client is still used by the tests as an independent check of this encoding.

Validation order follows the specification: function code (01), quantity and PDU shape (03),
address range (02, partly here for ranges past 65535, the rest by the register map).
"""
from __future__ import annotations

import enum
import struct
from dataclasses import dataclass

MBAP = struct.Struct(">HHHB")      # transaction id, protocol id (0), length, unit id
MBAP_SIZE = MBAP.size              # 7
MAX_PDU = 253                      # function code + data
MAX_LENGTH_FIELD = MAX_PDU + 1     # the MBAP length counts the unit id too
ADDRESS_SPACE = 0x10000

# Quantity limits of the specification (a PDU must fit in 253 bytes).
MAX_READ_BITS = 2000
MAX_READ_REGISTERS = 125
MAX_WRITE_BITS = 1968
MAX_WRITE_REGISTERS = 123
MAX_RW_WRITE_REGISTERS = 121

COIL_ON = 0xFF00
COIL_OFF = 0x0000

READ_COILS = 1
READ_DISCRETE_INPUTS = 2
READ_HOLDING_REGISTERS = 3
READ_INPUT_REGISTERS = 4
WRITE_SINGLE_COIL = 5
WRITE_SINGLE_REGISTER = 6
WRITE_MULTIPLE_COILS = 15
WRITE_MULTIPLE_REGISTERS = 16
READ_WRITE_MULTIPLE_REGISTERS = 23

ALL_FUNCTIONS = frozenset({1, 2, 3, 4, 5, 6, 15, 16, 23})


class ExceptionCode(enum.IntEnum):
    ILLEGAL_FUNCTION = 1
    ILLEGAL_DATA_ADDRESS = 2
    ILLEGAL_DATA_VALUE = 3
    SERVER_DEVICE_FAILURE = 4


class ModbusException(Exception):
    """A request refused with a Modbus exception response; `reason` is for logs, not the wire."""

    def __init__(self, code: ExceptionCode, reason: str = ""):
        self.code = ExceptionCode(code)
        self.reason = reason
        super().__init__(f"exception {int(code):02d} ({self.code.name}){': ' + reason if reason else ''}")


class Table(enum.Enum):
    """The four Modbus data tables; register maps decide what each one means."""

    COILS = "coils"
    DISCRETE_INPUTS = "discrete inputs"
    INPUT_REGISTERS = "input registers"
    HOLDING_REGISTERS = "holding registers"


@dataclass(frozen=True)
class Access:
    """One contiguous access to a table: `values` is set for a write, `count` for a read."""

    table: Table
    start: int
    count: int
    values: tuple[int, ...] = ()


@dataclass(frozen=True)
class Request:
    """A decoded request PDU. FC 23 has both a read and a write; the write is done first."""

    function: int
    read: Access | None = None
    write: Access | None = None
    echo: bytes = b""          # the PDU bytes FC 5/6 echo back


_ADDR_QTY = struct.Struct(">HH")
_ADDR_QTY_BC = struct.Struct(">HHB")
_RW = struct.Struct(">HHHHB")


def _value_error(reason: str) -> ModbusException:
    return ModbusException(ExceptionCode.ILLEGAL_DATA_VALUE, reason)


def _check_quantity(qty: int, limit: int, what: str) -> None:
    if not 1 <= qty <= limit:
        raise _value_error(f"{what} quantity {qty} not in 1..{limit}")


def _check_span(start: int, qty: int) -> None:
    if start + qty > ADDRESS_SPACE:
        raise ModbusException(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                              f"addresses {start}..{start + qty - 1} pass 65535")


def _fixed(data: bytes, size: int, function: int) -> None:
    if len(data) != size:
        raise _value_error(f"function {function} expects {size} data bytes, got {len(data)}")


def unpack_bits(data: bytes, count: int) -> list[int]:
    """Bits LSB first within each byte, as Modbus packs coils."""
    return [(data[i >> 3] >> (i & 7)) & 1 for i in range(count)]


def pack_bits(bits: list[int] | tuple[int, ...]) -> bytes:
    out = bytearray((len(bits) + 7) // 8)
    for i, bit in enumerate(bits):
        if bit:
            out[i >> 3] |= 1 << (i & 7)
    return bytes(out)


def decode_request(pdu: bytes, supported: frozenset[int] = ALL_FUNCTIONS) -> Request:
    """Decode a request PDU; raises ModbusException (01 unknown function, 03 bad shape/quantity,
    02 range past 65535)."""
    if not pdu:
        raise _value_error("empty PDU")
    function, data = pdu[0], pdu[1:]
    if function not in supported or function not in ALL_FUNCTIONS:
        raise ModbusException(ExceptionCode.ILLEGAL_FUNCTION, f"function {function} not supported")

    if function in (READ_COILS, READ_DISCRETE_INPUTS, READ_HOLDING_REGISTERS, READ_INPUT_REGISTERS):
        _fixed(data, 4, function)
        start, qty = _ADDR_QTY.unpack(data)
        bits = function in (READ_COILS, READ_DISCRETE_INPUTS)
        _check_quantity(qty, MAX_READ_BITS if bits else MAX_READ_REGISTERS, "read")
        _check_span(start, qty)
        table = {READ_COILS: Table.COILS, READ_DISCRETE_INPUTS: Table.DISCRETE_INPUTS,
                 READ_HOLDING_REGISTERS: Table.HOLDING_REGISTERS,
                 READ_INPUT_REGISTERS: Table.INPUT_REGISTERS}[function]
        return Request(function, read=Access(table, start, qty))

    if function == WRITE_SINGLE_COIL:
        _fixed(data, 4, function)
        address, value = _ADDR_QTY.unpack(data)
        if value not in (COIL_ON, COIL_OFF):
            raise _value_error(f"coil value 0x{value:04X} is neither 0xFF00 nor 0x0000")
        return Request(function, write=Access(Table.COILS, address, 1, (1 if value else 0,)),
                       echo=bytes(pdu))

    if function == WRITE_SINGLE_REGISTER:
        _fixed(data, 4, function)
        address, value = _ADDR_QTY.unpack(data)
        return Request(function, write=Access(Table.HOLDING_REGISTERS, address, 1, (value,)),
                       echo=bytes(pdu))

    if function in (WRITE_MULTIPLE_COILS, WRITE_MULTIPLE_REGISTERS):
        if len(data) < _ADDR_QTY_BC.size:
            raise _value_error(f"function {function} PDU too short ({len(pdu)} bytes)")
        start, qty, byte_count = _ADDR_QTY_BC.unpack_from(data)
        payload = data[_ADDR_QTY_BC.size:]
        if function == WRITE_MULTIPLE_COILS:
            _check_quantity(qty, MAX_WRITE_BITS, "write")
            expected = (qty + 7) // 8
        else:
            _check_quantity(qty, MAX_WRITE_REGISTERS, "write")
            expected = 2 * qty
        if byte_count != expected or len(payload) != expected:
            raise _value_error(f"byte count {byte_count} / {len(payload)} data bytes, "
                               f"{expected} expected for quantity {qty}")
        _check_span(start, qty)
        if function == WRITE_MULTIPLE_COILS:
            return Request(function, write=Access(Table.COILS, start, qty,
                                                  tuple(unpack_bits(payload, qty))))
        values = struct.unpack(f">{qty}H", payload)
        return Request(function, write=Access(Table.HOLDING_REGISTERS, start, qty, values))

    # READ_WRITE_MULTIPLE_REGISTERS
    if len(data) < _RW.size:
        raise _value_error(f"function 23 PDU too short ({len(pdu)} bytes)")
    read_start, read_qty, write_start, write_qty, byte_count = _RW.unpack_from(data)
    payload = data[_RW.size:]
    _check_quantity(read_qty, MAX_READ_REGISTERS, "read")
    _check_quantity(write_qty, MAX_RW_WRITE_REGISTERS, "write")
    if byte_count != 2 * write_qty or len(payload) != 2 * write_qty:
        raise _value_error(f"byte count {byte_count} / {len(payload)} data bytes, "
                           f"{2 * write_qty} expected for quantity {write_qty}")
    _check_span(read_start, read_qty)
    _check_span(write_start, write_qty)
    values = struct.unpack(f">{write_qty}H", payload)
    return Request(function,
                   read=Access(Table.HOLDING_REGISTERS, read_start, read_qty),
                   write=Access(Table.HOLDING_REGISTERS, write_start, write_qty, values))


def encode_response(request: Request, values: list[int] | None = None) -> bytes:
    """The normal response PDU of `request`; `values` are what its read returned."""
    function = request.function
    if function in (WRITE_SINGLE_COIL, WRITE_SINGLE_REGISTER):
        return request.echo
    if function in (WRITE_MULTIPLE_COILS, WRITE_MULTIPLE_REGISTERS):
        assert request.write is not None
        return struct.pack(">BHH", function, request.write.start, request.write.count)
    assert values is not None
    if function in (READ_COILS, READ_DISCRETE_INPUTS):
        payload = pack_bits(values)
    else:
        payload = struct.pack(f">{len(values)}H", *values)
    return struct.pack(">BB", function, len(payload)) + payload


def exception_response(function: int, code: ExceptionCode) -> bytes:
    return bytes(((function | 0x80) & 0xFF, int(code)))


def frame(transaction: int, unit: int, pdu: bytes) -> bytes:
    """A whole ADU: MBAP header + PDU, sent with one write so a one-read client gets it whole."""
    return MBAP.pack(transaction, 0, len(pdu) + 1, unit) + pdu
