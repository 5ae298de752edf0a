"""The MODBMAST TLM: a Modbus RTU/ASCII serial master driver configured by
MODBMAST.XML, with its diagnostic ladder instructions."""

from .module import Modbmast

__all__ = ["Modbmast"]
