"""Protobuf encoding by hand, shared by the attack scripts.

The attacks send frames the generated code would refuse to build (oversized
names, broken Start rules), so they encode the few fields they need themselves.
"""


def varint(value: int) -> bytes:
    """A base-128 varint, least significant group first."""
    out = b""
    while True:
        low, value = value & 0x7F, value >> 7
        if not value:
            return out + bytes([low])
        out += bytes([low | 0x80])


def length_delimited(field: int, payload: bytes) -> bytes:
    """A length-delimited field (wire type 2): a sub-message, string or bytes."""
    return bytes([field << 3 | 2]) + varint(len(payload)) + payload
