"""Serial ports for every module that drives them (COMGENIUS, MODBMAST, ...).

One layer below the modules:

- ``port.py``: ``SerialPort``, a port opened through ``serial_for_url``,
  read and written without blocking the scan, down and retried when its
  device fails; ``LineSettings``;
- ``naming.py``: ``COMn`` to devices, which device a port claims, and
  ``softplc run --port [MODULE:]N=DEVICE`` overrides;
- ``transports/``: how each kind of port moves bytes now (device, loop,
  socket, simulated);
- ``wire.py``, ``simdevices.py``, ``modbus_slave.py`` and ``urlhandler/``:
  the simulated wire (``sim://``) with its devices, and ``replay://``;
- ``trace.py`` and ``recorder.py``: port traces, ``--record`` and
  ``--replay``.

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
