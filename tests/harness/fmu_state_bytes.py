"""The serialized FMU state's documented layout, for tests that read, alter and re-pack serialized states.

Written from docs/fmi_layer.md ("FMU state"), not from the C: the build's instantiation
token with its NUL, then little-endian fields (u32 format, u32 interface type, u32
instance state, i64 method value, u32 count n, n float64 values: those of value
references 0..n-1, i.e. time, states, inputs, parameters), then the CRC-32 of IEEE
802.3 of all the bytes before it, which is zlib.crc32: an implementation independent of
the FMU's.
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass, replace

HEADER = struct.Struct("<IIIqI")  # format, interface type, instance state, method value, count
CO_SIMULATION, MODEL_EXCHANGE = 0, 1
# instance states as the serialized form numbers them (docs/fmi_layer.md, the order of §3's tables)
STATE_NUMBERS = {
    "Instantiated": 0,
    "InitializationMode": 1,
    "StepMode": 2,
    "EventMode": 3,
    "ContinuousTimeMode": 4,
    "Terminated": 5,
    "Error": 6,
}


@dataclass(frozen=True)
class StateBytes:
    """The fields of one serialized state; `pack` writes them back with a fresh CRC."""

    token: bytes  # with its NUL
    fmt: int
    interface: int
    state: int
    method: int
    values: tuple[float, ...]
    crc: int

    @classmethod
    def parse(cls, data: bytes) -> StateBytes:
        """Split serialized bytes into their fields (AssertionError if the sizes disagree)."""
        end = data.index(b"\0") + 1
        fmt, interface, state, method, n = HEADER.unpack_from(data, end)
        off = end + HEADER.size
        values = struct.unpack_from(f"<{n}d", data, off)
        (crc,) = struct.unpack_from("<I", data, off + 8 * n)
        assert off + 8 * n + 4 == len(data), f"{len(data)} bytes, the layout needs {off + 8 * n + 4}"
        return cls(data[:end], fmt, interface, state, method, values, crc)

    def body(self, count: int | None = None) -> bytes:
        """Everything the CRC covers; `count` overrides the count field (not the values)."""
        n = len(self.values) if count is None else count
        head = HEADER.pack(self.fmt, self.interface, self.state, self.method, n)
        return self.token + head + struct.pack(f"<{len(self.values)}d", *self.values)

    def pack(self, count: int | None = None) -> bytes:
        """The serialized bytes with the CRC-32 of the (possibly altered) fields."""
        body = self.body(count)
        return body + struct.pack("<I", zlib.crc32(body))

    def with_value(self, vr: int, value: float) -> StateBytes:
        """A copy with the value of value reference vr replaced."""
        values = list(self.values)
        values[vr] = value
        return replace(self, values=tuple(values))
