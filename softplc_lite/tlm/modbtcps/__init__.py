"""MODBTCPS: a Modbus TCP server over the data table, for HMIs and SCADA
(docs/modbtcps.md). A plug-in module (TLM) registered like COMGENIUS and
MODBMAST; the server is pymodbus's, run in a process of its own."""

from .module import ModbTcpServer

__all__ = ["ModbTcpServer"]
