"""I/O forcing, as on a PLC: a forced bit holds its forced value whatever
the input scan or the program writes.

Any bit address can be forced (I and O bits as on a PLC-5, and, for a soft
PLC's convenience, B, N or status bits too). The engine applies the forces
at both ends of every scan: after the input point (so the ladder reads the
forced inputs) and before the output point (so what goes out, and what the
data table shows between scans, is the forced value even if a rung wrote
the bit during the scan).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..datatable import DataTable, DataTableError, data_bit_mask, parse_address
from ..datatable.address import Address
from ..ladder.symbols import SymbolError, resolve_name
from .breakpoints import quoted


class ForceError(DataTableError):
    pass


@dataclass(frozen=True)
class Force:
    address: Address
    on: bool

    def __str__(self) -> str:
        return f"{self.address}={int(self.on)}"


def parse_force(text: str, symbols=None, prompt: bool = False) -> Force:
    """``ADDR=1`` or ``ADDR=0`` (ADDR a bit address or a program symbol).
    A ForceError names where the text came from: ``--force 'TEXT'``, or
    ``force TEXT`` as typed at the view's prompt (``prompt``)."""
    where = f"force {text}" if prompt else f"--force {quoted(text)}"
    example = "I:0/0=1" if prompt else "--force I:0/0=1"
    name, eq, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not eq or value not in ("0", "1"):
        raise ForceError(f"{where}: expected ADDR=1 or ADDR=0, e.g. {example}")
    try:
        address = resolve_name(name, symbols)
    except SymbolError as e:
        raise ForceError(f"{where}: {e.reason}") from None
    except DataTableError as e:
        raise ForceError(f"{where}: {e}") from None
    return Force(_bit_address(address, where), value == "1")


def _bit_address(address: Address, where: str) -> Address:
    if address.bit is None or not address.is_direct:
        raise ForceError(f"{where}: only a direct bit address can be forced (e.g. O:0/0, B3/5, N7:0/3)")
    return address


class Forces:
    """The forced bits of one engine, applied at its input and output points."""

    def __init__(self, engine) -> None:
        self.engine = engine
        self.table: DataTable = engine.table
        self.forces: dict[str, Force] = {}
        # address -> (word array, index, mask, on): one entry per force, so
        # setting or removing one costs the same however many there are
        self._resolved: dict[str, tuple[object, int, int, bool]] = {}
        self._hooked = False

    def set(self, force: Force) -> None:
        key = str(force.address)
        self.table.reference(force.address)  # forcing B3/40 creates the word, as a write would
        f, index, bit = self.table.resolve(force.address)
        self.forces[key] = force
        data = f.data
        mask = data_bit_mask(data, bit)
        self._resolved[key] = (data, index, mask, force.on)
        self._hook(True)
        data[index] = (data[index] | mask) if force.on else (data[index] & ~mask)  # at once, in the table shown

    def remove(self, address: str | Address) -> bool:
        key = str(address if isinstance(address, Address) else
                  _bit_address(parse_address(address), f"unforce {address}"))
        found = self.forces.pop(key, None) is not None
        self._resolved.pop(key, None)
        self._hook(bool(self._resolved))
        return found

    def clear(self) -> None:
        self.forces.clear()
        self._resolved.clear()
        self._hook(False)

    def listed(self) -> list[Force]:
        return [self.forces[k] for k in sorted(self.forces)]

    def _hook(self, on: bool) -> None:
        """The engine calls the forces only while there are some (a scan
        without forces pays nothing for them)."""
        engine = self.engine
        if on and not self._hooked:
            engine.input_hooks.append(self._apply_in)  # after the modules' input hooks
            engine.output_hooks.insert(0, self._apply_out)  # before any module sends
        elif not on and self._hooked:
            engine.input_hooks.remove(self._apply_in)
            engine.output_hooks.remove(self._apply_out)
        self._hooked = on

    def apply(self) -> None:
        for data, index, mask, on in self._resolved.values():
            w = data[index]
            data[index] = (w | mask) if on else (w & ~mask)

    def _apply_in(self, engine) -> None:
        if self._resolved:
            self.apply()

    def _apply_out(self, engine, enabled: bool) -> None:
        if self._resolved:
            self.apply()
