"""MODBTCPS: a Modbus TCP server over the data table, for HMIs and SCADA
(docs/modbtcps.md). A plug-in module (TLM) registered like COMGENIUS and
MODBMAST; the server is the network-server layer's (softplc_lite/netserver),
in a process of its own, with pymodbus framing Modbus."""

from .module import ModbTcpServer

__all__ = ["ModbTcpServer"]
