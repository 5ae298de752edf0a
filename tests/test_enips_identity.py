import struct

from helpers.cip import route
from softplc_lite.cip import cpf, epath, status
from softplc_lite.tlm.enips.identity import Identity, IdentityObject, serial_for
from softplc_lite.tlm.enips.router import MessageRouter


def ask(router, service, *path):
    return route(router, service, epath.encode_logical(*path))


def test_identity_attributes():
    router = MessageRouter([IdentityObject(Identity("PUMPS"))])
    whole = ask(router, 0x01, 1, 1)
    assert whole.status == 0
    vendor, device, product, major, minor, _, serial = struct.unpack_from("<HHHBBHI", whole.data)
    assert (vendor, device, major, minor) == (1, 0x0E, 1, 1)
    assert serial == serial_for("PUMPS") != serial_for("OTHER")
    name = whole.data[14:]
    assert name[1:1 + name[0]] == b"softplc_lite PUMPS"
    assert ask(router, 0x0E, 1, 1, 7).data == name
    assert ask(router, 0x0E, 1, 1, 9).status == status.ATTRIBUTE_NOT_SUPPORTED
    assert ask(router, 0x0E, 1, 2, 1).status == status.OBJECT_DOES_NOT_EXIST
    assert ask(router, 0x10, 1, 1, 1).status == status.SERVICE_NOT_SUPPORTED


def test_default_registration_serves_identity():
    assert ask(MessageRouter(), 0x0E, 1, 1, 1).data == b"\x01\x00"


def test_list_identity_item_round_trips():
    item = Identity("PUMPS").list_identity_item("127.0.0.1", 44818)
    [back] = cpf.decode(cpf.encode([item]))
    assert back.type_id == cpf.LIST_IDENTITY
    assert back.data[4:6] == struct.pack(">H", 44818)
    assert back.data[-1] == 3 and b"softplc_lite PUMPS" in back.data


def test_pycomm3_reads_the_list_identity_item():
    from pycomm3.custom_types import ListIdentityObject

    raw = cpf.encode([Identity("PUMPS").list_identity_item("127.0.0.1", 44818)])
    seen = ListIdentityObject.decode(raw[2:])  # pycomm3 skips the item count
    assert seen["product_name"] == "softplc_lite PUMPS"
    assert seen["ip_address"] == "127.0.0.1"
    assert seen["product_type"] == "Programmable Logic Controller"
