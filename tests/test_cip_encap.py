import pytest

from softplc_lite.cip import encap


def test_register_session_round_trip():
    # RegisterSession as pycomm3 sends it: protocol version 1, options 0.
    raw = bytes.fromhex("6500 0400 00000000 00000000") + b"ctx12345" + bytes(4) + bytes.fromhex("0100 0000")
    message = encap.EncapMessage.decode(raw)
    assert message.command == encap.REGISTER_SESSION
    assert message.data == bytes.fromhex("01000000")
    assert message.context == b"ctx12345"
    assert message.encode() == raw
    reply = message.reply(message.data, session=0x1234)
    assert encap.EncapHeader.decode(reply.encode()).session == 0x1234
    assert reply.encode()[12:20] == b"ctx12345"


def test_truncated_and_mislengthed():
    with pytest.raises(encap.EncapError, match="24 bytes, got 10"):
        encap.EncapHeader.decode(bytes(10))
    raw = encap.EncapMessage(encap.NOP, b"abc").encode()
    with pytest.raises(encap.EncapError, match="3 data bytes, got 2"):
        encap.EncapMessage.decode(raw[:-1])
