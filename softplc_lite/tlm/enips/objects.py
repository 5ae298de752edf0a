"""The CIP objects the ENIPS server routes requests to: a request as the
Message Router hands it over, the reply an object gives, and the object
interface (one class per CIP object, as pymodbus has one class per PDU).

An object with ``class_id`` None serves the requests whose path is
symbolic (an ANSI extended symbolic segment, 0x91): Logix tag services."""

from __future__ import annotations

import abc
from dataclasses import dataclass

from .access import TableAccess

REPLY = 0x80  # the reply bit of a service code


@dataclass(frozen=True)
class CipRequest:
    service: int  # the request's service code (no reply bit)
    path: bytes  # the request path as received (padded EPATH), for objects that parse it themselves
    logical: tuple[int | None, int | None, int | None]  # (class, instance, attribute) of a logical path
    data: bytes  # the request data after the path


@dataclass(frozen=True)
class CipReply:
    service: int  # the request's service | 0x80
    status: int = 0  # CIP general status (softplc_lite.cip.status)
    extended: tuple[int, ...] = ()  # additional status words
    data: bytes = b""

    @classmethod
    def ok(cls, request: CipRequest, data: bytes = b"") -> "CipReply":
        return cls(request.service | REPLY, 0, (), data)

    @classmethod
    def error(cls, request: CipRequest, status: int, *extended: int) -> "CipReply":
        return cls(request.service | REPLY, status, tuple(extended))


class CipObject(abc.ABC):
    """One CIP object class the server serves."""

    class_id: int | None = None

    @abc.abstractmethod
    async def serve(self, request: CipRequest, access: TableAccess) -> CipReply:
        """The reply to ``request``; never raises for a client's bad request
        (it is a status), only for a bug."""
