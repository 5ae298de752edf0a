"""The data table as the server process's requests see it (access.py's
``TableAccess``): reads from the image the scan published, all spans of one
request from one scan; writes passed to the scan's input point and answered
once applied (netserver's ``Server.read`` and ``Server.through_scan``)."""

from __future__ import annotations

from array import array

from .access import FileInfo, TableAccess
from .protocol import FileSlot, group_payload, mask_payload, write_payload


class ImageAccess(TableAccess):
    """``files_served`` False: no file is served as a file (a Logix app's
    table, reached through its tags only); reads and writes by name still are."""

    def __init__(self, server, slots: tuple[FileSlot, ...], files_served: bool = True) -> None:
        self.server = server
        self.slots = {s.info.name: s for s in slots}
        self._files = [s.info for s in slots] if files_served else []

    def files(self) -> list[FileInfo]:
        return self._files

    def writable(self, name: str, first: int, count: int) -> bool:
        slot = self.slots.get(name)
        return slot is not None and slot.may_write(first, count)

    def writable_bits(self, name: str, index: int, and_mask: int, or_mask: int) -> bool:
        slot = self.slots.get(name)
        return slot is not None and slot.may_mask(index, and_mask, or_mask)

    async def read(self, spans: list[tuple[str, int, int]]) -> list[list]:
        wanted, slots = [], []
        for name, first, count in spans:
            slot = self.slots[name]
            if first < 0 or count < 0 or first + count > slot.info.items:
                raise IndexError(f"{name}: items {first}..{first + count - 1} past its end ({slot.info.items} items)")
            wanted.append((slot.offset + first * slot.itemsize, count * slot.itemsize))
            slots.append(slot)
        out = []
        for slot, raw in zip(slots, await self.server.read(wanted)):
            items = array(slot.typecode)
            items.frombytes(raw)
            out.append(items.tolist())
        return out

    async def write(self, name: str, first: int, items: list) -> bool:
        slot = self.slots.get(name)
        if slot is None or not slot.may_write(first, len(items)):
            return False
        return await self.server.through_scan(write_payload(slot.info.number, first, array(slot.typecode, items)))

    async def write_masked(self, name: str, index: int, and_mask: int, or_mask: int) -> bool:
        slot = self.slots.get(name)
        if slot is None or not slot.may_mask(index, and_mask, or_mask):
            return False
        return await self.server.through_scan(mask_payload(slot.info.number, index, and_mask, or_mask))

    async def write_group(self, writes: list[tuple]) -> bool:
        payloads = []
        for name, first, *rest in writes:
            slot = self.slots.get(name)
            allowed = slot is not None and (slot.may_write(first, len(rest[0])) if len(rest) == 1
                                            else slot.may_mask(first, *rest))
            if not allowed:
                return False
            payloads.append(write_payload(slot.info.number, first, array(slot.typecode, rest[0])) if len(rest) == 1
                            else mask_payload(slot.info.number, first, *rest))
        return await self.server.through_scan(group_payload(payloads))
