"""The MODBMAST TLM: a Modbus RTU/ASCII serial master driver configured by
MODBMAST.XML, with its diagnostic ladder instructions (issue 13)."""

from .module import Modbmast

__all__ = ["Modbmast"]
