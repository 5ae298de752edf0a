import asyncio
import struct

from softplc_lite.cip import cpf, encap, epath
from softplc_lite.cip.encap import EncapMessage
from softplc_lite.cip.mr import MessageRouterRequest, MessageRouterResponse
from softplc_lite.tlm.enips.identity import Identity
from softplc_lite.tlm.enips.router import MessageRouter
from softplc_lite.tlm.enips.session import EncapSession


def talk(session, message):
    reply = asyncio.run(session.reply(EncapMessage.decode(message.encode())))
    return None if reply is None else EncapMessage.decode(reply.encode())


def rr(session_handle, request):
    body = bytes(6) + cpf.encode([cpf.Item(cpf.NULL_ADDRESS), cpf.Item(cpf.UNCONNECTED_DATA, request)])
    return EncapMessage(encap.SEND_RR_DATA, body, session_handle)


def test_session_lifecycle():
    s = EncapSession(MessageRouter(), None, Identity("PUMPS"))
    read_vendor = MessageRouterRequest(0x0E, epath.encode_logical(1, 1, 1)).encode()
    assert talk(s, rr(0, read_vendor)).status == encap.INVALID_SESSION
    reg = talk(s, EncapMessage(encap.REGISTER_SESSION, struct.pack("<HH", 1, 0), context=b"abcdefgh"))
    assert reg.status == encap.SUCCESS and reg.session and reg.context == b"abcdefgh"
    assert talk(s, EncapMessage(encap.REGISTER_SESSION, struct.pack("<HH", 1, 0))).status == encap.INCORRECT_DATA
    reply = talk(s, rr(reg.session, read_vendor))
    assert reply.status == 0
    items = cpf.decode(reply.data[6:])
    assert MessageRouterResponse.decode(items[1].data).data == b"\x01\x00"
    assert talk(s, rr(reg.session + 1, read_vendor)).status == encap.INVALID_SESSION
    assert talk(s, EncapMessage(0x01, b"", reg.session)).status == encap.INVALID_COMMAND
    assert talk(s, EncapMessage(encap.SEND_RR_DATA, b"\x00", reg.session)).status == encap.INCORRECT_DATA
    assert talk(s, EncapMessage(encap.UNREGISTER_SESSION, b"", reg.session)) is None
    assert talk(s, rr(reg.session, read_vendor)).status == encap.INVALID_SESSION


def test_unsupported_protocol_and_list_identity():
    s = EncapSession(MessageRouter(), None, Identity("PUMPS"))
    assert talk(s, EncapMessage(encap.REGISTER_SESSION, struct.pack("<HH", 2, 0))).status == encap.UNSUPPORTED_PROTOCOL
    [item] = cpf.decode(talk(s, EncapMessage(encap.LIST_IDENTITY)).data)
    assert b"softplc_lite PUMPS" in item.data
    [service] = cpf.decode(talk(s, EncapMessage(encap.LIST_SERVICES)).data)
    assert service.type_id == cpf.LIST_SERVICES and service.data.endswith(b"Communications\x00\x00")
