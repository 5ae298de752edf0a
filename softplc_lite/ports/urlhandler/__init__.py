"""pyserial URL handlers of softplc_lite: ``sim://`` and ``replay://``.

pyserial's ``serial.serial_for_url(url)`` imports ``protocol_<scheme>`` from
each package named in ``serial.protocol_handler_packages``. ``register()``
appends this package there (once: calling it again changes nothing), and
importing this package calls it, so after

    import softplc_lite.ports.urlhandler

``serial.serial_for_url("sim://bus")`` and ``serial.serial_for_url(
"replay://session.trace?port=0")`` open like ``loop://`` or ``socket://``.

- ``protocol_sim``: one end of a simulated link with wire timing, to another
  port or to a simulated device (simlink.py, wire.py, simdevices.py).
- ``protocol_replay``: plays back the received side of a trace file
  (trace.py) and checks what the program writes against it.

docs/simulated-wire.md describes both for users.
"""

from __future__ import annotations

import serial

PACKAGE = __name__


def register() -> None:
    """Add this package to pyserial's URL handler packages (idempotent)."""
    if PACKAGE not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append(PACKAGE)


register()
