"""Every place OPCUAS touches asyncua: this module, and the patches of its
classes in asyncua_patches.py.

Written and tested against asyncua >=2.1,<2.2 (the range pyproject.toml
pins: asyncua changes its API in minor releases). Beyond its documented
API (``Server``: ``init``, ``set_endpoint``, ``set_security_policy``,
``register_namespace``, ``start``, ``stop``; the ``ua`` types), OPCUAS
relies on these internals:

- ``Server.iserver`` (the ``InternalServer``): ``certificate_validator``, the
  one security.py set, wrapped to count its refusals; ``node_mgt_service.add_nodes``, to
  make the address space in one call; ``aspace.write_attribute_value``
  and ``aspace.read_attribute_value``, to publish a scan's values and to
  tell a known node from an unknown one; its limits ``max_connections``
  (one connection a session) and ``max_subscriptions``;
- ``iserver.attribute_service.write``, taken over: every Write service
  call comes here first (``Refuser``);
- ``iserver.subscription_service.create_subscription`` (to count its
  refusals), ``subscriptions``, ``create_monitored_items``,
  ``modify_monitored_items`` and
  ``subscriptions[..].monitored_item_srv._monitored_items``, to hold the
  monitored items to the configured limit and keep each one's sampling
  interval;
- ``Server.bserver._server`` (the asyncio server), for the port bound, and
  ``bserver.clients``, the connections open;
- the patches of asyncua's classes in asyncua_patches.py (installed once
  a process: on a connection, a session request, a password, a monitored
  item's data change), whose
  docstring lists the internals they rely on.

Nothing else in OPCUAS imports asyncua (asyncua_patches.py only through
this module). ``missing()`` says, in one line,
what an installed asyncua lacks of this; the server process reports it
instead of failing later with a traceback.
"""

from __future__ import annotations

import asyncio
import logging
from datetime import datetime, timezone

ASYNCUA_RANGE = ">=2.1,<2.2"

try:
    import asyncua
    from asyncua import Server, ua
    from asyncua.server.uaprocessor import UaProcessor
    from asyncua.crypto.permission_rules import User, UserRole
    from asyncua.server.binary_server_asyncio import OPCUAProtocol
    from asyncua.server.address_space import AddressSpace, AttributeService, NodeManagementService
    from asyncua.server.internal_server import InternalServer
    from asyncua.server.monitored_item_service import MonitoredItemService
    from asyncua.server.subscription_service import SubscriptionService
except ImportError as _exc:  # the server process says this line, not a traceback
    if isinstance(_exc, ModuleNotFoundError) and _exc.name == "asyncua":
        raise ImportError(f"asyncua is not installed: OPCUAS needs asyncua{ASYNCUA_RANGE} "
                          f"(pip install 'asyncua{ASYNCUA_RANGE}')") from None
    raise ImportError(f"the installed asyncua lacks what OPCUAS uses ({_exc}): OPCUAS is written for "
                      f"asyncua {ASYNCUA_RANGE} (pip install 'asyncua{ASYNCUA_RANGE}')") from None

from pathlib import Path  # noqa: E402

from . import writes  # noqa: E402
from .security import CertPaths, SecuritySettings, apply_security, role_of, user_can_write  # noqa: E402
from .users import FILE_NAME as USERS_FILE, Users  # noqa: E402
from .space import NAMESPACE, Space, decode  # noqa: E402
from .status import IDLE, MALFORMED, REFUSED_LIMIT, SKIPPED_SCANS  # noqa: E402
from .asyncua_patches import (ASIDE, COUNT, Sampler, check_passwords_aside, check_transport,  # noqa: E402
                               refuse_unoffered, sample_items)

_NEEDED = (
    (Server, ("init", "set_endpoint", "set_security_policy", "register_namespace", "start", "stop")),
    (AttributeService, ("write",)),
    (SubscriptionService, ("create_monitored_items", "create_subscription", "modify_monitored_items")),
    (MonitoredItemService, ("datachange_callback",)),
    (AddressSpace, ("write_attribute_value", "read_attribute_value")),
    (InternalServer, ("start",)),
    (UaProcessor, ("_process_message",)),
    (NodeManagementService, ("add_nodes",)),
    (OPCUAProtocol, ("connection_made", "data_received", "_process_one_msg", "_activation_watchdog")),
)
POLL_S = 0.002  # how often the server looks for a new scan in the image: a choice (docs/opcuas.md)
VARIANT = {"Boolean": ua.VariantType.Boolean, "Int16": ua.VariantType.Int16, "Int32": ua.VariantType.Int32,
           "Float": ua.VariantType.Float, "String": ua.VariantType.String, "SByte": ua.VariantType.SByte,
           "Int64": ua.VariantType.Int64, "Mode": ua.VariantType.String}
DATA_TYPE = {"Boolean": ua.ObjectIds.Boolean, "Int16": ua.ObjectIds.Int16, "Int32": ua.ObjectIds.Int32,
             "Float": ua.ObjectIds.Float, "String": ua.ObjectIds.String, "SByte": ua.ObjectIds.SByte,
             "Int64": ua.ObjectIds.Int64, "Mode": ua.ObjectIds.String}
BAD_NOT_WRITABLE = ua.StatusCodes.BadNotWritable
BAD_NODE_UNKNOWN = ua.StatusCodes.BadNodeIdUnknown
BAD_TOO_MANY_ITEMS = ua.StatusCodes.BadTooManyMonitoredItems


async def end_clock(server) -> None:
    """Stop the task asyncua's InternalServer keeps ServerStatus.CurrentTime
    with: it sleeps a second between updates and ``Server.stop`` awaits it,
    so a runtime's stop (and every test's) would wait up to a second."""
    iserver = server.iserver
    task = getattr(iserver, "time_task", None)
    if task is None:
        return
    iserver._time_task_stop = True
    task.cancel()
    try:
        await task
    except asyncio.CancelledError:
        pass
    iserver.time_task = None


def sampling_s(requested_ms: float, publishing_ms: float) -> float:
    """The seconds between an item's samples, as OPC 10000-4 5.12.1.2 has a
    requested SamplingInterval revised: -1 is the subscription's publishing
    interval; 0, or less than the server looks for a new scan (POLL_S), is
    every scan (the fastest the values change). 0.0: every scan."""
    ms = publishing_ms if requested_ms < 0 else requested_ms
    return ms / 1000.0 if ms / 1000.0 > POLL_S else 0.0


def _keep_sampling(subs, subscription_id: int, items, created: bool = True) -> None:
    """Give each item created or modified its sampling interval, revised as
    ``sampling_s`` says, and say it in its result. ``items``: (monitored
    item id, its requested parameters, its result). A created item's first
    sample is the value asyncua sent it on creation."""
    sub = subs.subscriptions.get(subscription_id)
    if sub is None:
        return
    for item_id, requested, result in items:
        mdata = sub.monitored_item_srv._monitored_items.get(item_id)
        if mdata is None or not result.StatusCode.is_good():
            continue
        interval = sampling_s(requested.SamplingInterval, sub.data.RevisedPublishingInterval)
        result.RevisedSamplingInterval = 1000.0 * (interval or POLL_S)
        old = getattr(mdata, "sampler", None)
        if not interval:
            mdata.sampler = None
        elif old is not None:
            old.interval = interval
        else:
            mdata.sampler = Sampler(interval, asyncio.get_running_loop().time() + interval if created else 0.0)


def missing() -> str | None:
    """What the installed asyncua lacks of what this module uses, in one
    line; None when it has everything."""
    lacking = [f"{owner.__name__}.{name}" for owner, names in _NEEDED for name in names if not hasattr(owner, name)]
    if not lacking:
        return None
    return (f"asyncua {getattr(asyncua, '__version__', '?')} lacks {', '.join(lacking)}: OPCUAS is written "
            f"for asyncua {ASYNCUA_RANGE} (pip install 'asyncua{ASYNCUA_RANGE}')")


def _add_items(space: Space, ns: int) -> list:
    """The AddNodes items of the whole address space, parents first."""
    items = []
    obj_type = ua.NodeId(ua.ObjectIds.BaseObjectType)
    var_type = ua.NodeId(ua.ObjectIds.BaseDataVariableType)
    for o in space.objects:
        attrs = ua.ObjectAttributes(DisplayName=ua.LocalizedText(o.name), Description=ua.LocalizedText(o.description))
        parent = ua.NodeId(o.parent, ns) if o.parent else ua.NodeId(ua.ObjectIds.ObjectsFolder)
        ref = ua.ObjectIds.HasComponent if o.parent else ua.ObjectIds.Organizes
        items.append(ua.AddNodesItem(RequestedNewNodeId=ua.NodeId(o.node, ns),
                                     BrowseName=ua.QualifiedName(o.name, ns), NodeClass=ua.NodeClass.Object,
                                     ParentNodeId=parent, ReferenceTypeId=ua.NodeId(ref),
                                     TypeDefinition=obj_type, NodeAttributes=attrs))
    read, write = ua.AccessLevel.CurrentRead.mask, ua.AccessLevel.CurrentWrite.mask
    for v in space.variables:
        access = read | write if v.writable else read
        attrs = ua.VariableAttributes(
            DisplayName=ua.LocalizedText(v.name), Description=ua.LocalizedText(v.description),
            Value=ua.Variant(_empty(v.kind), VARIANT[v.kind]), DataType=ua.NodeId(DATA_TYPE[v.kind]),
            ValueRank=-1, AccessLevel=access, UserAccessLevel=access)
        items.append(ua.AddNodesItem(RequestedNewNodeId=ua.NodeId(v.node, ns), BrowseName=ua.QualifiedName(v.name, ns),
                                     NodeClass=ua.NodeClass.Variable, ParentNodeId=ua.NodeId(v.parent, ns),
                                     ReferenceTypeId=ua.NodeId(ua.ObjectIds.HasComponent),
                                     TypeDefinition=var_type, NodeAttributes=attrs))
    return items


def _empty(kind: str):
    return {"Boolean": False, "String": "", "Mode": "", "Float": 0.0}.get(kind, 0)


class Listener:
    """asyncua's server, as the network-server layer's listener
    (netserver.protocol.Listener): ``start`` makes the address space and
    listens, then follows the scans the image publishes."""

    def __init__(self, server, space: Space, config, counters) -> None:
        self.plc_server = server
        self.space = space
        self.config = config
        self.counters = counters  # (refused writes, monitored items, subscriptions, identities)
        self.ua: Server | None = None
        self.ns = 2
        self.task: asyncio.Task | None = None
        self.nodes: list = []
        self.notified = 0  # values published to asyncua: one per variable per scan at most
        self.by_node = {v.node: v for v in space.variables}
        self.may_write = user_can_write  # a write user or a trusted certificate (security.py)
        self.manager = None  # security.py's UserManager: the identities it refused
        self._last_seq, self._last_raw, self._values = None, None, [None] * len(space.variables)
        self._by_slot: list[list[int]] | None = None

    async def start(self) -> int:
        for name in ("asyncua", "asyncua.server", "asyncua.uaprotocol"):
            logging.getLogger(name).setLevel(logging.CRITICAL)  # this server says what matters, counted
        s = self.plc_server.settings
        server = self.ua = Server()
        await server.init()
        host = f"[{s.host}]" if ":" in s.host else s.host
        server.set_endpoint(f"opc.tcp://{host}:{s.port}/")
        server.set_server_name(f"softplc_lite {self.space.app}")
        await self._secure(server)
        self.ns = await server.register_namespace(NAMESPACE)
        iserver = server.iserver
        iserver.max_connections = self.config.max_sessions
        # A connection that opens no session within idleTimeout is closed (asyncua waits 30 s):
        # config.py says why.
        iserver.max_pending_activation_seconds = self.config.idle_timeout_ms / 1000
        iserver.max_subscriptions = self.config.max_subscriptions
        iserver.allow_remote_admin = False  # a client calling itself "admin" gets no more than another
        results = iserver.node_mgt_service.add_nodes(_add_items(self.space, self.ns))
        bad = [r.StatusCode for r in results if not r.StatusCode.is_good()]
        if bad:
            raise RuntimeError(f"asyncua refused {len(bad)} nodes of the address space ({bad[0].name})")
        self.nodes = [ua.NodeId(v.node, self.ns) for v in self.space.variables]
        self._take_over(iserver)
        count = self.plc_server.count
        for kind, counter in (("limit", REFUSED_LIMIT), ("malformed", MALFORMED), ("idle", IDLE)):
            COUNT[kind] = lambda message, counter=counter: count(counter, message)
        check_transport()
        await server.start()
        self.task = asyncio.get_running_loop().create_task(self.follow())
        return server.bserver._server.sockets[0].getsockname()[1]

    async def _secure(self, server) -> None:
        """security.py's policy, from the config and the files beside it
        (OPCUAS.PKI/, OPCUAS.USERS); a refused identity counted. Writes are
        refused per item by ``write_one`` (BadUserAccessDenied, counted), not
        by the ruleset as a whole request."""
        c = self.config
        app_dir = Path(c.path).parent
        settings = SecuritySettings(allow_none=c.allow_none, allow_sign=c.allow_sign, anonymous=c.anonymous,
                                    trusted_clients_only=c.trusted_clients_only)
        manager = self.manager = await apply_security(server, settings, Users.load(app_dir / USERS_FILE),
                                                      CertPaths.for_app(app_dir), refuse_writes=False)
        get_user, counter, count = manager.get_user, self.counters[3], self.plc_server.count

        def checked(iserver, username=None, password=None, certificate=None):
            user = get_user(iserver, username=username, password=password, certificate=certificate)
            if user is None:
                count(counter, f"session refused: {'user ' + repr(username) if username is not None else 'identity'}")
            return user
        manager.get_user = checked
        validate = server.iserver.certificate_validator

        async def counted(cert, app_description) -> None:  # an untrusted or invalid client certificate
            try:
                await validate(cert, app_description)
            except ua.UaStatusCodeError as e:
                count(counter, f"session refused: client certificate {type(e).__name__}")
                raise
        server.set_certificate_validator(counted)
        COUNT["channel"] = lambda message: count(counter, message)
        ASIDE["manager"] = manager
        check_passwords_aside()
        refuse_unoffered()  # after: a session on a channel not offered is refused before its password is checked

    async def stop(self) -> None:
        if self.task is not None:
            self.task.cancel()
        if self.ua is not None:
            await end_clock(self.ua)
            await self.ua.stop()

    # -- the scans ---------------------------------------------------------------------------
    async def follow(self) -> None:
        """Publish each scan's values as the image holds them, the changed
        ones only: a monitored item gets at most one change a scan."""
        while True:
            await self.refresh()
            await asyncio.sleep(POLL_S)

    async def refresh(self) -> None:
        """Take the latest whole scan from the image, if it is new, and give
        asyncua the values it changed. The scans published since the last
        one taken, before this one, are counted skipped while a client is
        subscribed: their changes reached no subscriber (a server that
        falls behind the scan)."""
        image, space = self.plc_server.image, self.space
        if self._by_slot is None:
            self._by_slot = [[] for _ in space.slots]
            for i, v in enumerate(space.variables):
                self._by_slot[v.slot].append(i)
        while True:
            seq = image.sequence()
            if seq == self._last_seq:
                return
            raws = None if seq & 1 else image.read([(0, space.image_bytes)])
            if raws is not None:
                break
            await asyncio.sleep(0)  # the scan is publishing: a few microseconds
        last_seq = self._last_seq
        if last_seq is not None and seq > last_seq + 2 and self.ua.iserver.subscription_service.subscriptions:
            # each scan's publication moves the sequence by 2; counted while a subscription waits for
            # changes (a Read takes the newest scan whatever came between: nothing is missed)
            self.plc_server.image.add(SKIPPED_SCANS, (seq - last_seq) // 2 - 1)
        raw, last_raw, values = raws[0], self._last_raw, self._values
        aspace = self.ua.iserver.aspace
        now = datetime.now(timezone.utc)
        for k, slot in enumerate(space.slots):
            end = slot.offset + slot.items * slot.itemsize
            if last_raw is not None and raw[slot.offset:end] == last_raw[slot.offset:end]:
                continue
            for i in self._by_slot[k]:
                v = space.variables[i]
                value = decode(v, raw)
                if value != values[i] or last_raw is None:
                    values[i] = value
                    dv = ua.DataValue(ua.Variant(value, VARIANT[v.kind]), SourceTimestamp=now, ServerTimestamp=now)
                    await aspace.write_attribute_value(self.nodes[i], ua.AttributeIds.Value, dv)
                    self.notified += 1
        self._last_seq, self._last_raw = seq, raw
        image.set(0, len(self.ua.bserver.clients))  # counters.CONNECTED

    async def write_one(self, wv, user) -> int:
        """The status code of one Write operation on a node of the PLC's."""
        v = self.by_node.get(wv.NodeId.Identifier) if isinstance(wv.NodeId.Identifier, str) else None
        if v is None or not v.writable or wv.AttributeId != ua.AttributeIds.Value:
            return BAD_NOT_WRITABLE
        if not self.may_write(user):  # a refusal the caller counts, with whose it was
            return ua.StatusCodes.BadUserAccessDenied
        variant = wv.Value.Value if wv.Value is not None else None
        if variant is None or variant.VariantType != VARIANT[v.kind] or wv.IndexRange:
            return ua.StatusCodes.BadTypeMismatch
        refusal, payload = writes.check(self.space, v, variant.Value)
        if refusal is not None:
            return getattr(ua.StatusCodes, refusal)
        if self.plc_server.busy() is not None:
            return ua.StatusCodes.BadTooManyOperations
        if not await self.plc_server.through_scan(payload):
            return ua.StatusCodes.BadOutOfRange
        await self.refresh()  # answered once applied: a read that follows sees it
        return ua.StatusCodes.Good

    # -- refusals ----------------------------------------------------------------------------
    def _take_over(self, iserver) -> None:
        aspace = iserver.aspace
        service = iserver.attribute_service
        original_write = service.write
        ns = self.ns
        refused_write, refused_items, refused_subscriptions = self.counters[:3]
        count = self.plc_server.count

        async def write(params, user=User(role=UserRole.User)):
            """Every Write: a node of the PLC's that no <Writable> opens is
            read-only (BadNotWritable: its AccessLevel has no CurrentWrite,
            OPC 10000-4 5.10.4), one it opens goes through the scan
            (``write_one``); an unknown node BadNodeIdUnknown; asyncua's own nodes as asyncua
            rules for a user who is not its admin. Only asyncua's own
            internal session is admin (``allow_remote_admin`` is off)."""
            if user.role == UserRole.Admin:
                return await original_write(params, user)
            results = []
            for wv in params.NodesToWrite:
                known = aspace.read_attribute_value(wv.NodeId, ua.AttributeIds.NodeClass)
                if known.StatusCode is not None and not known.StatusCode.is_good():
                    count(refused_write, f"write to {wv.NodeId.to_string()}: no such node")
                    results.append(ua.StatusCode(BAD_NODE_UNKNOWN))
                elif wv.NodeId.NamespaceIndex == ns:
                    code = await self.write_one(wv, user)
                    if code != ua.StatusCodes.Good:
                        count(refused_write, f"write to {wv.NodeId.to_string()} by {role_of(user)}: "
                                             f"{ua.StatusCode(code).name}")
                    results.append(ua.StatusCode(code))
                else:
                    one = ua.WriteParameters(NodesToWrite=[wv])
                    results += await original_write(one, User(role=UserRole.User))
            return results

        service.write = write
        subs = iserver.subscription_service
        original_items = subs.create_monitored_items
        limit = self.config.max_monitored_items

        async def create_monitored_items(params):
            held = sum(len(s.monitored_item_srv._monitored_items) for s in subs.subscriptions.values())
            room = max(0, limit - held)
            asked = list(params.ItemsToCreate)
            if len(asked) > room:  # asyncua makes the ones there is room for; the rest refused below
                params = params.__class__(SubscriptionId=params.SubscriptionId,
                                          TimestampsToReturn=params.TimestampsToReturn, ItemsToCreate=asked[:room])
            results = await original_items(params) if room or not asked else []
            _keep_sampling(subs, params.SubscriptionId,
                           [(r.MonitoredItemId, a.RequestedParameters, r) for a, r in zip(asked, results)])
            for _ in asked[room:]:
                count(refused_items, f"monitored item over maxMonitoredItems={limit}")
                results.append(ua.MonitoredItemCreateResult(StatusCode=ua.StatusCode(BAD_TOO_MANY_ITEMS)))
            return results

        subs.create_monitored_items = create_monitored_items
        original_modify = subs.modify_monitored_items

        def modify_monitored_items(params):
            results = original_modify(params)
            _keep_sampling(subs, params.SubscriptionId, [(m.MonitoredItemId, m.RequestedParameters, r)
                                                         for m, r in zip(params.ItemsToModify, results)], False)
            return results

        subs.modify_monitored_items = modify_monitored_items
        sample_items()
        original_subscription = subs.create_subscription

        async def create_subscription(params, callback, session_id, request_callback=None):
            if len(subs.subscriptions) >= iserver.max_subscriptions:  # asyncua refuses it: counted here
                count(refused_subscriptions, f"subscription over maxSubscriptions={iserver.max_subscriptions}")
            return await original_subscription(params, callback, session_id, request_callback)

        subs.create_subscription = create_subscription
