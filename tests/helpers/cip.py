"""One Message Router request through a router, as a client's bytes would
go: encoded, handled, and the response decoded (the CIP object tests)."""

from __future__ import annotations

import asyncio

from softplc_lite.cip.mr import MessageRouterRequest, MessageRouterResponse


def route(router, service: int, path: bytes, data: bytes = b"", access=None) -> MessageRouterResponse:
    raw = MessageRouterRequest(service, path, data).encode()
    return MessageRouterResponse.decode(asyncio.run(router.handle(raw, access)))
