"""Serial ports for every module that drives them (COMGENIUS, MODBMAST, ...).

One layer below the modules, in three parts:

Ports, whatever their kind:

- ``port.py``: ``SerialPort``, a port opened through ``serial_for_url``,
  read and written without blocking the scan, down and retried when its
  device fails; ``LineSettings``;
- ``naming.py``: ``COMn`` to devices, which device a port claims, and
  ``softplc run --port [MODULE:]N=DEVICE`` overrides;
- ``transports/``: how each kind of port moves its bytes without blocking
  (device, loop, socket, simulated).

The simulated line (``sim://``) and its devices:

- ``wire.py``: character timing, the bytes in flight on one direction;
- ``simlink.py``: links between two ends, found by name;
- ``clocked.py``: the pyserial port on a given clock (``sim://`` and
  ``replay://`` both are);
- ``simdevices.py``, ``modbus_slave.py``, ``modbus_master.py``: the devices;
- ``urlhandler/protocol_sim.py``: the ``sim://`` URL.

Traces:

- ``trace.py``: the trace file; ``recorder.py``: ``--record``;
- ``urlhandler/protocol_replay.py``: ``replay://``, for ``--replay``.

docs/serial.md and docs/simulated-wire.md describe them for users.
"""

from .naming import (COM_NAME, OverrideError, PortClaim, assign_port_overrides, claim_conflicts, claim_key,
                     com_url, default_com_device, parse_port_overrides, physical_url)
from .port import PORT_ERRORS, LineSettings, SerialPort, hexdump
from .recorder import Recorder

__all__ = [
    "COM_NAME", "PORT_ERRORS", "LineSettings", "OverrideError", "PortClaim", "Recorder", "SerialPort",
    "assign_port_overrides", "claim_conflicts", "claim_key", "com_url", "default_com_device", "hexdump",
    "parse_port_overrides", "physical_url",
]
